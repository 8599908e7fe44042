"""The wiring every baseline shares behind the :class:`~hsqbench.planner.api.Planner` protocol,
and the input step they share with the hsq planner (cleaning, :func:`clean_input`)."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from hsqbench.planner.api import (
    PlanningContext,
    PlanResult,
    resolve_config,
    resolve_gripper,
    validate_cloud,
)
from hsqbench.planner.baselines.config import BaselinesConfig, resolve_baselines_config
from hsqbench.planner.cleaning import (
    CleanedCloud,
    CleaningConfig,
    all_removed_reason,
    clean_cloud,
)
from hsqbench.planner.gripper import GripperModel


@dataclass(frozen=True)
class CleanInput:
    """A validated cloud after the hsq planner's cleaning (``cleaning:`` of the planner config).

    Attributes:
        points: (M, 3) the points kept, metres.
        source: (N,) for each of the caller's points, the row of ``points`` it was merged into
            (-1: removed); see :class:`~hsqbench.planner.cleaning.CleanedCloud`.
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
        """The result when cleaning left no point (the hsq planner answers the same)."""
        return PlanResult(
            grasps=[],
            timings={"cleaning": self.seconds, "total": self.seconds},
            reason=all_removed_reason(self.n_input, config),
            planner=planner,
            n_removed=self.n_input,
        )


def clean_input(points: ArrayLike, config: CleaningConfig) -> CleanInput:
    """Validate ``points``, thin them and remove isolated points (flying pixels) as the hsq planner does
    (:func:`~hsqbench.planner.cleaning.clean_cloud`), so that a stray point in a finger's path
    removes a baseline's grasp no more than hsq's.

    Raises:
        ValueError: an empty, non-finite or badly shaped cloud.
    """
    start = time.perf_counter()
    raw = validate_cloud(points)
    cleaned = clean_cloud(raw, config)
    return CleanInput(cleaned.points, cleaned, int(raw.shape[0]), time.perf_counter() - start)


class BaselinePlanner:
    """A baseline's plan function with its config and gripper resolved once.

    Subclasses set ``name`` and ``plan_function``, a callable with the signature of
    ``plan_single_sq``: ``(points, config, *, packed, support_plane, seed, gripper,
    camera_positions)``. The gripper defaults to the one named by the planner config the
    baselines share with hsq. The context reaches the baselines as it reaches hsq: the table,
    the packed flag, the seed and the cameras (contacts none of them sees need no support).
    """

    name: ClassVar[str]
    plan_function: ClassVar[Callable[..., PlanResult]]

    def __init__(
        self,
        config: BaselinesConfig | str | Path | None = None,
        gripper: GripperModel | None = None,
    ) -> None:
        self.config = resolve_baselines_config(config)
        grasp = resolve_config(self.config.planner).grasp
        self.gripper = gripper if gripper is not None else resolve_gripper(grasp.gripper)

    def plan(self, points: ArrayLike, context: PlanningContext) -> PlanResult:
        return type(self).plan_function(
            points, self.config, gripper=self.gripper, **context.plan_kwargs()
        )
