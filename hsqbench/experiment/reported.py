"""Numbers reported in the paper, shown beside our measurements.

Source: Y. Wu, W. Liu, Z. Liu, G. S. Chirikjian, "Learning-Free Grasping of Unknown Objects Using
Hidden Superquadrics", Table I (isolated objects, 150 attempts) and Table II (packed scenes,
15 rounds of 5 objects). All rows are real-robot results; the baselines' numbers are those the
paper quotes from other work (other robots, objects and setups), so they are context, not a
like-for-like comparison with our simulation.

They describe the paper's 15 objects only, so a run on other objects (the unseen-object
protocols) shows none of them: :func:`reported_rows` reads them from the run's ``run.json``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

CITATION = (
    "Wu, Liu, Liu, Chirikjian, Learning-Free Grasping of Unknown Objects Using Hidden "
    "Superquadrics, Tables I and II"
)
PROVENANCE = "reported, real robot"


@dataclass(frozen=True)
class ReportedRow:
    """One method's reported rates, in percent (``None`` where the paper gives none)."""

    method: str
    experiment: str  # "isolated" or "packed"
    gsr_percent: float
    cr_percent: float | None = None
    reference: str = ""


REPORTED: tuple[ReportedRow, ...] = (
    ReportedRow("6-DOF GraspNet", "isolated", 88.0, reference="Mousavian et al. 2019"),
    ReportedRow("GPD", "isolated", 47.0, reference="ten Pas et al. 2017"),
    ReportedRow("PointNetGPD", "isolated", 82.0, reference="Liang et al. 2019"),
    ReportedRow("HSQ (paper)", "isolated", 96.0, reference="this paper"),
    ReportedRow("GIGA", "packed", 83.3, 86.6, reference="Jiang et al. 2021"),
    ReportedRow("HSQ (paper)", "packed", 81.3, 81.3, reference="this paper"),
)


@cache
def paper_objects() -> frozenset[str]:
    """The objects of the paper's Tables I and II (the ``paper`` protocol's isolated list)."""
    from hsqbench.experiment.config import load_experiment_config

    return frozenset(load_experiment_config("paper").isolated.objects)


def reported_rows(experiment: str, meta: dict | None = None) -> tuple[ReportedRow, ...]:
    """The paper's rows for ``experiment``; none when the run of ``meta`` (its ``run.json``)
    gave that experiment objects that are not all the paper's. Without a stored config (or
    without ``meta``) the objects are not known and every row is returned."""
    objects = _run_objects(meta or {}, experiment)
    if objects is not None and not set(objects) <= paper_objects():
        return ()
    return tuple(r for r in REPORTED if r.experiment == experiment)


def _run_objects(meta: dict, experiment: str) -> list[str] | None:
    """The objects a run's stored config gives ``experiment`` (None when it holds no config)."""
    config = meta.get("config")
    return None if not config else list(config.get(experiment, {}).get("objects", []))
