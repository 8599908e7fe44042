"""The two protocols: an isolated trial (one object, one attempt) and a packed round (attempts
until the table is clear or the stop rule ends the round)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from hsqbench.sim.motion import SimUnstable
from hsqbench.sim.objects import ObjectLike
from hsqbench.sim.outcome import Attempt, Outcome, RoundResult, TrialResult
from hsqbench.sim.recorder import Recorder
from hsqbench.sim.trial.attempt import AttemptTrace, resolve_planner, run_attempt
from hsqbench.sim.trial.config import TrialConfig, load_trial_config
from hsqbench.sim.trial.env import TrialEnv
from hsqbench.sim.trial.release import return_home


def _planner_name(planner: Any) -> str:
    return (
        planner
        if isinstance(planner, str)
        else str(getattr(planner, "name", type(planner).__name__))
    )


def _clear(env: TrialEnv) -> tuple[list[str], dict[str, str]]:
    """Take out of the scene, with the hand at home, the objects in the bin (cleared), those
    still on the hand (carried away, as an operator would take them off it) and those out of
    the workspace (fallen off the table or out of the cameras' view); the last two are not
    cleared. Returns the cleared names and the others' names with why."""
    cleared, lost = [], {}
    carried = env.probe.on_robot(env.data)
    for name in env.info.objects:
        if name in env.removed:
            continue
        if name in carried:
            lost[name] = "stayed on the hand"
        elif env.probe.in_bin(env.data, name):
            cleared.append(name)
        elif not env.probe.in_workspace(env.data, name):
            lost[name] = "left the workspace"
        else:
            continue
        env.remove(name)
    return cleared, lost


def run_isolated_trial(
    object: str | ObjectLike,
    seed: int,
    planner: Any = "hsq",
    config: TrialConfig | None = None,
    *,
    recorder: Recorder | None = None,
    traces: list[AttemptTrace] | None = None,
) -> TrialResult:
    """One object at the seed's random upright pose, one attempt (the paper's isolated protocol).

    Args:
        object: an object name (``hsqbench.assets.library``) or an object.
        seed: the only source of randomness.
        planner: a planner name (``hsqbench.planner.registry.planner_names()``) or a ``Planner``.
        config: default ``configs/trial.yaml``.
        recorder: episode recorder (default: none).
        traces: if given, the attempt's :class:`AttemptTrace` is appended to it.
    """
    cfg = config if config is not None else load_trial_config()
    if cfg.clutter is not None:
        raise ValueError(
            "the clutter-removal protocol (trial config clutter: set) has packed and pile rounds "
            "only: disable isolated in the protocol"
        )
    plan = resolve_planner(planner, cfg)
    with TrialEnv.build("isolated", object, seed, cfg, recorder) as env:
        attempt, trace = run_attempt(env, plan, packed=False)
        trace.scene_build_s = env.build_s
        name = env.info.objects[0]
        settle_s, speed = env.info.settle_time_s, env.info.max_speed_after_settle
    if traces is not None:
        traces.append(trace)
    return TrialResult(
        object=name,
        seed=seed,
        planner=_planner_name(planner),
        attempts=[attempt],
        scene_settle_s=float(settle_s),
        scene_max_speed=float(speed),
    )


def run_packed_round(
    objects: Sequence[str | ObjectLike] | None,
    seed: int,
    planner: Any = "hsq",
    config: TrialConfig | None = None,
    *,
    recorder: Recorder | None = None,
    traces: list[AttemptTrace] | None = None,
    kind: str = "packed",
) -> RoundResult:
    """A packed round: the objects placed apart (drawn by seed when ``objects`` is None), then
    attempts until the stop rule (:mod:`hsqbench.sim.stop_rule`, ``packed:`` of the config)
    ends it: no object left on the table, ``max_consecutive_failures`` in a row, the attempt
    cap, or an unstable simulation.

    Objects in the bin after an attempt are cleared; objects out of the workspace (fallen off the
    table, or pushed or dropped out of the cameras' view) are taken out but not cleared, as in
    VGN's clutter removal: no planner could see them. ``h_delta`` is off
    (``PlanningContext.packed``). ``kind="pile"``: the same round on a pile scene (:mod:`hsqbench.sim.scene.pile`) under the config's ``pile:`` rule.
    """
    if kind not in ("packed", "pile"):
        raise ValueError(f"a clutter-removal round is packed or pile, got {kind!r}")
    cfg = config if config is not None else load_trial_config()
    if cfg.clutter is not None:
        from hsqbench.sim.clutter.protocol import run_clutter_round

        return run_clutter_round(objects or [], seed, planner, cfg, kind)
    rule = cfg.pile if kind == "pile" else cfg.packed
    plan = resolve_planner(planner, cfg)
    attempts: list[Attempt] = []
    cleared: list[str] = []
    lost_all: list[str] = []
    graspable: list[str] | None = None
    outcomes: list[str] = []
    with TrialEnv.build(kind, objects, seed, cfg, recorder) as env:
        while rule.stop_reason(outcomes, bool(env.objects_on_table())) is None:
            attempt, trace = run_attempt(env, plan, packed=True)
            if not attempts:
                trace.scene_build_s = env.build_s
                graspable = trace.graspable_objects
            attempts.append(attempt)
            outcomes.append(attempt.outcome.value)
            if traces is not None:
                traces.append(trace)
            if attempt.outcome == Outcome.SIM_UNSTABLE:
                break
            try:
                return_home(env)
            except SimUnstable as exc:
                attempt.detail += f"; then the simulation became unstable going home: {exc}"
                break
            if attempt.outcome == Outcome.SUCCESS and not env.probe.in_bin(
                env.data, attempt.target
            ):
                attempt.detail += "; then carried out of the bin by the hand going home"
            done, lost = _clear(env)
            cleared += done
            lost_all += list(lost)
            for name, why in lost.items():
                attempt.detail += f"; {name} {why} (taken out, not cleared)"
        names = list(env.info.objects)
        settle_s, speed = env.info.settle_time_s, env.info.max_speed_after_settle
    return RoundResult(
        objects=names,
        seed=seed,
        planner=_planner_name(planner),
        attempts=attempts,
        objects_cleared=cleared,
        objects_graspable=graspable,
        objects_lost=lost_all,
        scene_settle_s=float(settle_s),
        scene_max_speed=float(speed),
    )
