"""Re-execute recorded grasps: a trial of a run played again with the grasps its
``attempts.csv`` recorded (``grasp_pose``, ``grasp_flipped``, ``width_m``) in place of its
planner, so a researcher can check a row, watch it (``--rerun``) or ask whether a change of the
execution settings turns its outcome, without planning again.

The scene is the trial's own (its seed and objects, the trial config of ``run.json``), so the
cloud, the oracle and the physics are those of the run. A packed or pile round is replayed from
its first attempt up to the one asked for, each attempt with its recorded grasp (an attempt
that found no grasp finds none again). The replay is exact when the executed grasp was the
first one motion-planned (``ranks_tried`` 1): otherwise the run's inverse kinematics had drawn
restarts for the grasps tried before it, so the replay's arm may take a slightly different
branch, and a borderline attempt may end differently (:attr:`ReplayedAttempt.exact` says which).

With ``replan`` the trial's own planner plans again at the recorded seed instead (a change of
the planner or the perception shows; a run made before the grasp columns can be replayed so).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from hsqbench.experiment.rows import numbers
from hsqbench.planner.api import PlanResult
from hsqbench.planner.grasp import Grasp
from hsqbench.sim.ik_types import Pose
from hsqbench.sim.outcome import Attempt
from hsqbench.sim.recorded_pose import from_pose7
from hsqbench.sim.stop_rule import NO_GRASP


class ReplayError(ValueError):
    """A row cannot be replayed (written before the grasp columns, or not a finished attempt)."""


def recorded_grasp(row: dict[str, str]) -> Grasp | None:
    """The planner's grasp of an attempt row (the executed one turned back when
    ``grasp_flipped``), or None when the attempt found no grasp.

    Raises:
        ReplayError: the row has no ``grasp_pose`` although a grasp was planned (a run made
            before the grasp columns).
    """
    if row.get("outcome") in NO_GRASP:  # no grasp was motion-planned: nothing to re-execute
        return None
    field = row.get("grasp_pose", "")
    if not field:
        raise ReplayError(
            f"attempt {row['trial_key']}#{row['attempt_index']} has no grasp_pose: the run was "
            "made before attempts.csv recorded grasp poses; re-plan it instead with "
            "`hsqbench replay --run RUN --replan`"
        )
    position, rotation = from_pose7(numbers(field))
    pose = Pose(position, rotation)
    if row.get("grasp_flipped") == "1":
        pose = pose.flipped()
    width = float(row["width_m"]) if row.get("width_m") else 0.0
    score = float(row["score"]) if row.get("score") else 0.0
    return Grasp(
        pose.position,
        pose.rotation,
        width if math.isfinite(width) else 0.0,
        score if math.isfinite(score) else 0.0,
    )


class RecordedGrasps:
    """A planner that plans nothing: its k-th call returns the k-th recorded grasp (none after
    the last). Privileged, so a recorded grasp is executed even on a cloud too small for a
    perceiving planner (the run's planner may have been the oracle)."""

    name = "recorded"
    privileged = True

    def __init__(self, grasps: Sequence[Grasp | None]) -> None:
        self.grasps = list(grasps)
        self.calls = 0

    def plan(self, points: Any, context: Any) -> PlanResult:
        k, self.calls = self.calls, self.calls + 1
        grasp = self.grasps[k] if k < len(self.grasps) else None
        if grasp is None:
            return PlanResult(grasps=[], reason="no grasp recorded", planner=self.name)
        return PlanResult(grasps=[grasp], planner=self.name)


@dataclass(frozen=True)
class ReplayedAttempt:
    """One recorded attempt and its replay.

    Attributes:
        key, index: the trial key and the attempt's index in it.
        recorded, replayed: the outcomes; ``detail``: the replay's detail.
        exact: the replay draws the run's IK restarts (``ranks_tried`` 1, or unknown).
        attempt: the replayed :class:`~hsqbench.sim.outcome.Attempt` (None: not reached).
    """

    key: str
    index: int
    recorded: str
    replayed: str
    detail: str
    exact: bool
    attempt: Attempt | None = None

    @property
    def same(self) -> bool:
        return self.recorded == self.replayed


def trial_rows(rows: Sequence[dict[str, str]], key: str) -> list[dict[str, str]]:
    """The attempt rows of trial ``key`` in attempt order.

    Raises:
        ReplayError: the run has no finished trial ``key``, or it errored.
    """
    chosen = sorted(
        (r for r in rows if r["trial_key"] == key), key=lambda r: int(r["attempt_index"])
    )
    if not chosen:
        example = rows[0]["trial_key"] if rows else "isolated/hsq/s0/mug/000"
        raise ReplayError(f"the run has no finished trial {key!r}; keys look like {example!r}")
    if chosen[0]["status"] != "ok":
        raise ReplayError(f"trial {key!r} did not run ({chosen[0]['detail']}): nothing to replay")
    return chosen


def replay_trial(
    rows: Sequence[dict[str, str]],
    trial_config: Any,
    upto: int | None = None,
    recorder: Any = None,
    replan: bool = False,
) -> list[ReplayedAttempt]:
    """Re-execute the recorded grasps of one trial's rows (:func:`trial_rows`), attempts
    ``0..upto`` (default: all), and pair each replayed attempt with its row. With ``replan``
    the trial's planner plans again instead (same seed and scene, so exact)."""
    from hsqbench.sim.trial import run_isolated_trial, run_packed_round

    first = rows[0]
    last = len(rows) - 1 if upto is None else upto
    if not 0 <= last < len(rows):
        raise ReplayError(f"trial {first['trial_key']} has attempts 0..{len(rows) - 1}, not {upto}")
    planner = (
        first["planner"]
        if replan
        else RecordedGrasps([recorded_grasp(r) for r in rows[: last + 1]])
    )
    seed, objects = int(first["seed"]), [o for o in first["objects"].split(";") if o]
    if first["experiment"] == "isolated":
        result = run_isolated_trial(objects[0], seed, planner, trial_config, recorder=recorder)
    else:
        result = run_packed_round(
            objects, seed, planner, trial_config, recorder=recorder, kind=first["experiment"]
        )
    replayed: list[Attempt] = result.attempts[: last + 1]
    out = []
    for row, attempt in zip(rows[: last + 1], replayed, strict=False):
        out.append(
            ReplayedAttempt(
                key=row["trial_key"],
                index=int(row["attempt_index"]),
                recorded=row["outcome"],
                replayed=str(attempt.outcome),
                detail=attempt.detail,
                exact=replan or row.get("ranks_tried", "") in ("", "0", "1"),
                attempt=attempt,
            )
        )
    for row in rows[len(replayed) : last + 1]:  # the replayed round stopped earlier
        out.append(
            ReplayedAttempt(
                row["trial_key"],
                int(row["attempt_index"]),
                row["outcome"],
                "not reached",
                "the replayed round stopped before it",
                exact=True,
            )
        )
    return out


@dataclass(frozen=True)
class TrialFilter:
    """Which finished trials of a run to replay: every field left empty keeps all.

    Attributes:
        outcome: a trial with an attempt of this recorded outcome.
        planner: a trial of this planner.
        detail: a trial with an attempt whose detail contains this text.
        failed_graspable: a trial with a failed attempt on a graspable presentation.
    """

    outcome: str = ""
    planner: str = ""
    detail: str = ""
    failed_graspable: bool = False

    def keeps(self, row: dict[str, str]) -> bool:
        """Whether attempt ``row`` qualifies its trial."""
        return (
            row["status"] == "ok"
            and (not self.outcome or row["outcome"] == self.outcome)
            and (not self.planner or row["planner"] == self.planner)
            and self.detail in row.get("detail", "")
            and (not self.failed_graspable or (row["graspable"], row["success"]) == ("1", "0"))
        )


def select_trials(rows: Sequence[dict[str, str]], chosen: TrialFilter) -> list[str]:
    """The keys of the trials (isolated attempts, packed or pile rounds) with an attempt that
    ``chosen`` keeps, in the run's row order."""
    return list(dict.fromkeys(r["trial_key"] for r in rows if chosen.keeps(r)))


def run_rows(run_dir: str | Path) -> list[dict[str, str]]:
    """The finished attempt rows of a run folder (read only)."""
    from hsqbench.experiment.results import ATTEMPTS_FILE, load_results
    from hsqbench.experiment.rows import has_attempts

    run = Path(run_dir)
    if not has_attempts(run):
        raise FileNotFoundError(f"{run} has no {ATTEMPTS_FILE}: not a benchmark run folder")
    return load_results(run).attempts
