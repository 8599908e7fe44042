"""Numbers reported in the paper, shown beside our measurements.

Source: Y. Wu, W. Liu, Z. Liu, G. S. Chirikjian, "Learning-Free Grasping of Unknown Objects Using
Hidden Superquadrics", Table I (isolated objects, 150 attempts) and Table II (packed scenes,
15 rounds of 5 objects). All rows are real-robot results; the baselines' numbers are those the
paper quotes from other work (other robots, objects and setups), so they are context, not a
like-for-like comparison with our simulation.
"""

from __future__ import annotations

from dataclasses import dataclass

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


def reported_rows(experiment: str) -> tuple[ReportedRow, ...]:
    return tuple(r for r in REPORTED if r.experiment == experiment)
