"""The one front door of the cloud planners: validate, clean, time and assemble.

Every planner that reads the cloud (hsq and its ablations, the baselines, contact-graspnet)
subclasses :class:`PlannerBase` and supplies only its own stages (:meth:`PlannerBase.stages`,
given the cleaned cloud and the whole :class:`~hsqbench.planner.api.PlanningContext`). The base
validates the cloud, cleans it as the hsq planner does (:func:`clean_input`), answers an empty
cleaned cloud for every planner alike, and assembles the result: the planner's name, the points
removed, and the timings (``cleaning`` first, ``total`` last).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from hsqbench.planner.cleaning import (
    CleanedCloud,
    CleaningConfig,
    all_removed_reason,
    clean_cloud,
)
from hsqbench.planner.hsq.stage_two.candidates import REJECTION_REASONS
from hsqbench.planner.hsq.stage_two.elimination import RULE_DESCRIPTIONS

if TYPE_CHECKING:
    from hsqbench.planner.api import PlanningContext, PlanResult


@dataclass(frozen=True)
class CleanInput:
    """A validated cloud after the hsq planner's cleaning (``cleaning:`` of the planner config).

    Attributes:
        points: (M, 3) the points kept, metres.
        cleaned: the cleaning's record (which input points went where).
        n_input: points the caller gave.
        seconds: wall-clock time of validation and cleaning.
    """

    points: NDArray[np.float64]
    cleaned: CleanedCloud
    n_input: int
    seconds: float

    @property
    def n_removed(self) -> int:
        return self.cleaned.n_removed

    def input_indices(self, rows: NDArray[np.int64]) -> NDArray[np.int64]:
        """The caller's points merged into ``rows`` of ``points``."""
        return self.cleaned.input_indices(rows)

    def empty_result(self, config: CleaningConfig, planner: str) -> PlanResult:
        """The result when cleaning left no point (every planner answers the same)."""
        from hsqbench.planner.api import PlanResult

        return PlanResult(
            grasps=[],
            timings={"cleaning": self.seconds, "total": self.seconds},
            reason=all_removed_reason(self.n_input, config),
            planner=planner,
            n_removed=self.n_input,
        )


def clean_input(points: ArrayLike, config: CleaningConfig) -> CleanInput:
    """Validate ``points``, thin them and remove isolated points (flying pixels) as the hsq
    planner does (:func:`~hsqbench.planner.cleaning.clean_cloud`), so that a stray point in a
    finger's path removes a baseline's grasp no more than hsq's.

    Raises:
        ValueError: an empty, non-finite or badly shaped cloud.
    """
    from hsqbench.planner.api import validate_cloud

    start = time.perf_counter()
    raw = validate_cloud(points)
    cleaned = clean_cloud(raw, config)
    return CleanInput(cleaned.points, cleaned, int(raw.shape[0]), time.perf_counter() - start)


def rules_removed_reason(counts: dict[str, int], prefix: str) -> str:
    """``prefix`` + which elimination rules removed how many candidates, and what the last rule
    that removed any checks (the shared end of every planner's "no grasp" reason)."""
    removed = ", ".join(f"{r} {counts[r]}" for r in REJECTION_REASONS if counts[r])
    last = next(r for r in reversed(REJECTION_REASONS) if counts[r])
    return f"{prefix}{removed}; the last were removed by '{last}' ({RULE_DESCRIPTIONS[last]})"


class PlannerBase:
    """A cloud planner behind the :class:`~hsqbench.planner.api.Planner` protocol.

    Subclasses set ``name`` (or an instance attribute), :meth:`cleaning_config` and
    :meth:`stages`; :meth:`plan` is the same for all.
    """

    name: ClassVar[str] | str

    def cleaning_config(self) -> CleaningConfig:
        """The cleaning every input cloud gets (the hsq planner's, for a fair comparison)."""
        raise NotImplementedError

    def stages(self, clean: CleanInput, context: PlanningContext) -> PlanResult:
        """The planner's own stages on the cleaned cloud; their timings in the result."""
        raise NotImplementedError

    def plan(self, points: ArrayLike, context: PlanningContext) -> PlanResult:
        """Validate and clean ``points``, run :meth:`stages`, and assemble the result."""
        start = time.perf_counter()
        cleaning = self.cleaning_config()
        clean = clean_input(points, cleaning)
        if clean.points.shape[0] == 0:
            return clean.empty_result(cleaning, self.name)
        result = self.stages(clean, context)
        result.planner = self.name
        result.n_removed = clean.n_removed
        result.timings = {"cleaning": clean.seconds, **result.timings}
        result.timings["total"] = time.perf_counter() - start
        return result


def context_of(**kwargs: Any) -> PlanningContext:
    """A :class:`~hsqbench.planner.api.PlanningContext` from the keyword arguments of the
    function forms (``plan_grasps(points, packed=..., support_plane=..., ...)``)."""
    from hsqbench.planner.api import PlanningContext

    return PlanningContext(**kwargs)
