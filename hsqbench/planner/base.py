"""The one front door of the cloud planners: validate, clean, time and assemble.

Every planner that reads the cloud (hsq and its ablations, the baselines, contact-graspnet)
subclasses :class:`PlannerBase` and supplies only its own stages (:meth:`PlannerBase.stages`,
given the cleaned cloud and the whole :class:`~hsqbench.planner.api.PlanningContext`). The base
validates the cloud, cleans it as the hsq planner does (:func:`clean_input`), answers an empty
cleaned cloud for every planner alike, and assembles the result: the planner's name, the points
removed, and the timings (``cleaning`` first, ``total`` last).
"""

from __future__ import annotations

import abc
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
from hsqbench.planner.failure import check_result
from hsqbench.planner.gripper import resolve_gripper
from hsqbench.planner.hsq.config import GraspConfig, resolve_config
from hsqbench.planner.hsq.stage_two.candidates import (
    REJECTION_REASONS,
    CandidateSet,
    ClosingLines,
)
from hsqbench.planner.hsq.stage_two.elimination import RULE_DESCRIPTIONS, eliminate

if TYPE_CHECKING:
    from collections.abc import Sequence

    from hsqbench.planner.api import PlanningContext, PlanResult
    from hsqbench.planner.grasp import Grasp


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


class PlannerBase(abc.ABC):
    """A cloud planner behind the :class:`~hsqbench.planner.api.Planner` protocol: the
    contract a planner of your own subclasses (docs/your-own-planner.md).

    Required: ``name`` (a class or instance attribute: the name in results) and
    :meth:`stages` (abstract: a class without it cannot be built, and the error names it).
    Opt-in: :meth:`cleaning_config` (default: hsq's cleaning) and :meth:`apply_rules` (the
    harness's elimination rules on your grasps). :meth:`plan` is the same for all.
    """

    name: ClassVar[str] | str

    def cleaning_config(self) -> CleaningConfig:
        """The cleaning every input cloud gets: by default the hsq planner's (``cleaning:`` of
        ``configs/planner.yaml``), for a fair comparison; override to clean otherwise."""
        return resolve_config(None).cleaning

    @abc.abstractmethod
    def stages(self, clean: CleanInput, context: PlanningContext) -> PlanResult:
        """The planner's own stages on the cleaned cloud: its grasps, best first, and the
        timings of its stages."""

    def apply_rules(
        self, grasps: Sequence[Grasp], clean: CleanInput, context: PlanningContext
    ) -> PlanResult:
        """Opt in to the harness's elimination rules: :func:`apply_rules` on ``grasps``."""
        return apply_rules(grasps, clean.points, context)

    def plan(self, points: ArrayLike, context: PlanningContext) -> PlanResult:
        """Validate and clean ``points``, run :meth:`stages`, and assemble the result."""
        start = time.perf_counter()
        cleaning = self.cleaning_config()
        clean = clean_input(points, cleaning)
        if clean.points.shape[0] == 0:
            return clean.empty_result(cleaning, self.name)
        result = self.stages(clean, context)
        check_result(self, result, "stages")
        result.planner = self.name
        result.n_removed = clean.n_removed
        result.timings = {"cleaning": clean.seconds, **result.timings}
        result.timings["total"] = time.perf_counter() - start
        return result


def apply_rules(
    grasps: Sequence[Grasp],
    points: NDArray[np.float64],
    context: PlanningContext,
    config: GraspConfig | None = None,
) -> PlanResult:
    """``grasps`` less those the harness's rules remove, best score first.

    The rules hsq's candidates go through (duplicate, width, support, table, collision,
    approach sweep: :mod:`~hsqbench.planner.hsq.stage_two.elimination`) with hsq's stage-two
    settings (``config``, default ``grasp:`` of ``configs/planner.yaml``) and gripper, against
    ``points`` (the cleaned cloud), with the context's table and cameras (a contact no camera
    sees needs no support). ``contact-graspnet-elim`` is the same idea for the network's grasps.
    """
    from hsqbench.planner.api import PlanResult, validate_cameras, validate_plane

    start = time.perf_counter()
    cfg = config if config is not None else resolve_config(None).grasp
    n = len(grasps)
    if n == 0:
        return PlanResult(grasps=[], reason="the planner proposed no grasp")
    rotations = np.stack([g.rotation for g in grasps])
    lines = ClosingLines(
        centres=np.stack([g.position for g in grasps]),
        directions=rotations[:, :, 0],
        approach0=rotations[:, :, 2],
        half_lengths=0.5 * np.array([g.width for g in grasps]),
        source=np.full(n, -1, dtype=np.int64),
        axis=np.full(n, -1, dtype=np.int64),
        family=np.full(n, "own", dtype="<U12"),
    )
    cands = CandidateSet(lines, np.zeros(1))  # one roll: the grasp as given
    report = eliminate(
        cands,
        points,
        resolve_gripper(cfg.gripper),
        cfg,
        validate_plane(context.support_plane),
        0 if context.seed is None else int(context.seed),
        camera_positions=validate_cameras(context.camera_positions),
    )
    cands.scores = np.where(cands.kept, np.array([g.score for g in grasps]), np.nan)
    ranked = cands.ranked()
    counts = cands.counts_by_reason()
    return PlanResult(
        grasps=ranked,
        candidates=cands,
        remaining=report.remaining,
        removed_by={r: counts[r] for r in REJECTION_REASONS},
        timings={"elimination": time.perf_counter() - start},
        reason=""
        if ranked
        else rules_removed_reason(counts, f"no grasp survived: of {n} grasps, the rules removed "),
    )


def context_of(**kwargs: Any) -> PlanningContext:
    """A :class:`~hsqbench.planner.api.PlanningContext` from the keyword arguments of the
    function forms (``plan_grasps(points, packed=..., support_plane=..., ...)``)."""
    from hsqbench.planner.api import PlanningContext

    return PlanningContext(**kwargs)
