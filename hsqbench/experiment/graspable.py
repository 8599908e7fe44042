"""Rates over graspable presentations, the oracle's coverage, and the privileged rows.

Graspability is decided once per scene that every planner shares, so no planner's denominator
depends on what it did:

- an isolated presentation (the object settled from the trial's seed, the same for every
  planner) is graspable when the oracle finds a feasible grasp on the true meshes
  (``attempts.csv`` column ``graspable``); GSR over graspable presentations is over these;
- a packed or pile round's objects are graspable when the oracle finds a grasp on them in the
  round's initial scene (``rounds.csv`` ``objects_graspable``, before the first attempt, the
  same for every planner); CR over graspable objects counts those. Later attempts' scenes
  depend on the planner, so no packed GSR is conditioned on graspability.

The oracle is a ceiling only if it plans wherever some planner succeeded: :func:`coverage_from_rows`
counts that, and :func:`ungraspable_successes` what each planner grasped that it calls
ungraspable.
"""

from __future__ import annotations

from dataclasses import dataclass

import pandas as pd

from hsqbench.experiment.results import STATUS_OK
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
    """GSR over the graspable presentations among isolated ``attempts`` (None when there are
    none)."""
    if (attempts["experiment"] != "isolated").any():
        raise ValueError("GSR over graspable presentations is defined on isolated trials only")
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


@dataclass(frozen=True)
class Coverage:
    """``covered`` of ``grasped`` (presentation, object) pairs; per experiment in ``parts``."""

    covered: int
    grasped: int
    parts: dict[str, tuple[int, int]]

    @property
    def percent(self) -> float:
        return 100.0 * self.covered / self.grasped if self.grasped else float("nan")

    def line(self, experiment: str | None = None) -> str:
        """One sentence: over every experiment, or over ``experiment`` alone."""
        if experiment is None:
            covered, grasped = self.covered, self.grasped
            parts = " (" + ", ".join(f"{e} {c}/{g}" for e, (c, g) in self.parts.items()) + ")"
        else:
            (covered, grasped), parts = self.parts[experiment], ""
        share = 100.0 * covered / grasped if grasped else float("nan")
        what = "presentations" if experiment in (None, "isolated") else "initial-scene objects"
        return (
            f"The oracle plans on {share:.1f} % of the {what} some planner grasped "
            f"({covered}/{grasped}{parts})."
        )


def _names(field: object) -> set[str]:
    return {n for n in str(field).split(";") if n and n != "nan"}


def grasped_presentations(attempts: pd.DataFrame) -> pd.DataFrame:
    """One row per (experiment, objects, seed, object) that some planner grasped: the object
    of an isolated trial, or a round's object that some attempt grasped (``target`` of a
    success)."""
    ok = attempts[(attempts["status"] == STATUS_OK) & (attempts["success"] == 1)]
    rows = ok[["experiment", "objects", "seed", "target"]].drop_duplicates()
    return rows.rename(columns={"target": "object"}).reset_index(drop=True)


def coverage_from_rows(attempts: pd.DataFrame, rounds: pd.DataFrame) -> Coverage | None:
    """Coverage of the run's own graspability verdicts (None: the run did not check): an
    isolated presentation by its ``graspable`` flag, a round's object by whether it is in
    ``objects_graspable`` (the round's initial scene, the same for every planner)."""
    checked = attempts[attempts["graspable"].notna()]
    if checked.empty:
        return None
    flag = checked.groupby(
        [checked["experiment"], checked["objects"], checked["seed"].astype(str)]
    )["graspable"].first()
    start: dict[tuple[str, str, str], set[str]] = {}
    if len(rounds) and "objects_graspable" in rounds:
        for r in rounds[rounds["status"] == STATUS_OK].itertuples():
            kind = str(r.trial_key).split("/", 1)[0]
            start.setdefault((kind, str(r.objects), str(r.seed)), _names(r.objects_graspable))
    parts: dict[str, list[int]] = {}
    for r in grasped_presentations(attempts).itertuples():
        key = (r.experiment, r.objects, str(r.seed))
        if r.experiment == "isolated":
            if key not in flag.index:
                continue
            covered = flag[key] == 1
        elif key in start:
            covered = r.object in start[key]
        else:
            continue
        part = parts.setdefault(r.experiment, [0, 0])
        part[0] += int(covered)
        part[1] += 1
    if not parts:
        return None
    return Coverage(
        sum(c for c, _ in parts.values()),
        sum(g for _, g in parts.values()),
        {e: (c, g) for e, (c, g) in parts.items()},
    )


def ungraspable_successes(attempts: pd.DataFrame, rounds: pd.DataFrame) -> pd.DataFrame:
    """Per experiment and planner, what it grasped of what the oracle calls ungraspable:
    isolated presentations with ``graspable`` 0 (``successes`` of ``presented``), and in rounds
    the objects not graspable in the round's initial scene (objects grasped at some attempt, of
    those presented). Columns ``experiment, planner, successes, presented``."""
    ok = attempts[attempts["status"] == STATUS_OK]
    rows = []
    iso = ok[(ok["experiment"] == "isolated") & (ok["graspable"] == 0)]
    for p, g in iso.groupby("planner", sort=False):
        rows.append(("isolated", p, int(g["success"].sum()), len(g)))
    if len(rounds) and "objects_graspable" in rounds:
        done = rounds[(rounds["status"] == STATUS_OK) & rounds["objects_graspable"].notna()]
        won = ok[(ok["experiment"] != "isolated") & (ok["success"] == 1)]
        grasped = won.groupby([won["planner"], won["seed"].astype(str), won["objects"]])[
            "target"
        ].agg(set)
        counts: dict[tuple[str, str], list[int]] = {}
        for r in done.itertuples():
            kind = str(r.trial_key).split("/", 1)[0]
            outside = _names(r.objects) - _names(r.objects_graspable)
            got = grasped.get((r.planner, str(r.seed), r.objects), set())
            c = counts.setdefault((kind, str(r.planner)), [0, 0])
            c[0] += len(outside & got)
            c[1] += len(outside)
        rows += [(e, p, k, n) for (e, p), (k, n) in counts.items()]
    return pd.DataFrame(rows, columns=["experiment", "planner", "successes", "presented"])


def method_label(planner: str) -> str:
    return f"{planner} (privileged)" if planner in PRIVILEGED else planner
