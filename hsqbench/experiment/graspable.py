"""Rates over graspable presentations only, and the privileged rows.

A presentation (an isolated trial, or one attempt of a packed round) is graspable when the
oracle found a feasible grasp on the true meshes (``attempts.csv`` column ``graspable``; every
planner sees the same pose, since the pose comes from the trial's seed). GSR over graspable
presentations leaves out what this hand cannot grasp at all; CR over graspable objects counts,
per round, the objects the oracle could grasp in the settled scene.
"""

from __future__ import annotations

import pandas as pd

from hsqbench.experiment.stats import Rate
from hsqbench.planner.registry import PRIVILEGED

#: Label of rows whose planner reads simulator truth (the oracle).
PRIVILEGED_NOTE = "privileged: reads the true meshes (a ceiling, not a method)"


def has_graspability(attempts: pd.DataFrame) -> bool:
    """Whether the run checked graspability (older runs and runs with the check off did not)."""
    return len(attempts) > 0 and bool(attempts["graspable"].notna().any())


def graspable_only(attempts: pd.DataFrame) -> pd.DataFrame:
    return attempts[attempts["graspable"] == 1]


def gsr_graspable(attempts: pd.DataFrame, confidence: float) -> Rate | None:
    """GSR over the graspable attempts of ``attempts`` (None when there are none)."""
    g = graspable_only(attempts)
    return Rate.of(int(g["success"].sum()), len(g), confidence) if len(g) else None


def cr_graspable(rounds: pd.DataFrame, confidence: float) -> Rate | None:
    """Objects cleared among those graspable at the round's start, over the rounds."""
    cleared = presented = 0
    for _, r in rounds.iterrows():
        graspable = {n for n in str(r.get("objects_graspable", "")).split(";") if n}
        if not graspable:
            continue
        presented += len(graspable)
        cleared += len(graspable & {n for n in str(r["objects_cleared"]).split(";") if n})
    return Rate.of(cleared, presented, confidence) if presented else None


def method_label(planner: str) -> str:
    return f"{planner} (privileged)" if planner in PRIVILEGED else planner
