"""Where a trial's seconds go: exclusive wall and CPU time per step of the trial, measured by
wrapping the functions that do each step (for ``bench_trial.py``; nothing here changes what a
trial computes).

A wrapped call opens a *step* (scene build, perception, planning, ...) or, inside one, a *part*
(compile, settle, render, IK, physics, ...). Each second is counted once, in the innermost
wrapped call running at that moment (its exclusive time), under ``(step, part)``; time inside a
step but in no part is the step's ``rest``, time in no step (the trial's own bookkeeping, the
executor, results rows) is ``other``. CPU time is the process's (``time.process_time``: every
thread, so the software GL renderer's threads count too).

Physics stepped by the trial's stepper is split by the phase it ran in (pregrasp, approach,
close, lift, carry, release, home): a step costs several times more with an object in the hand
(the no-slip pass on the finger contacts) than with the arm moving in free air, so the phase
says what a setting would buy.
"""

from __future__ import annotations

import functools
import importlib
import time
from collections import defaultdict
from collections.abc import Callable
from typing import Any

#: The part of physics stepped outside any stepper phase (scene settling, rest checks).
PHYSICS = "physics (mj_step)"


def _phase_physics(args: tuple[Any, ...], outer: str) -> str:
    """``Stepper.step``'s part: physics, named by the stepper's phase."""
    return f"{PHYSICS}: {args[0].phase or 'no phase'}"


def _physics(args: tuple[Any, ...], outer: str) -> str:
    """``mj_step``'s part: the phase's when a stepper called it, else plain physics."""
    return outer if outer.startswith(PHYSICS) else PHYSICS


#: A part: a name, or a function of the call's positional arguments and the enclosing part.
Part = str | Callable[[tuple[Any, ...], str], str] | None

#: (module, attribute path, step or None, part or None): a step opens a step; a part names the
#: time inside one. Attributes are patched where the caller looks them up.
WRAPPED: tuple[tuple[str, str, str | None, Part], ...] = (
    ("hsqbench.sim.trial.env", "TrialEnv.build", "scene build", "assets, layout, compose"),
    ("hsqbench.sim.scene.build", "compile_settled", None, "compile"),
    ("hsqbench.sim.scene.settled", "come_to_rest", None, "settle"),
    ("hsqbench.sim.scene.build", "settled_pile", None, "pile drop and settle"),
    ("hsqbench.sim.trial.env", "TrialEnv.__init__", None, "IK, probe, stepper set-up"),
    ("hsqbench.sim.trial.env", "TrialEnv.observe", "perception", "noise, back-project, fuse"),
    ("hsqbench.sim.trial.env", "TrialEnv._make_sensor", None, "renderer set-up"),
    ("hsqbench.sim.depth_renderer", "DepthRenderer.depth", None, "render and read depth"),
    ("hsqbench.sim.trial.env", "TrialEnv.truth", "graspability", "true hulls"),
    ("hsqbench.sim.trial.env", "TrialEnv.graspable_objects", "graspability", "oracle search"),
    ("hsqbench.sim.trial.attempt", "_plan", "planning", "planner"),
    ("hsqbench.sim.trial.attempt", "plan_motions", "motion planning", None),
    ("hsqbench.sim.trial.attempt", "execute_grasp", "execution", None),
    ("hsqbench.sim.trial.protocols", "_return_home", "return home", None),
    ("hsqbench.sim.trial.protocols", "_clear", "clear the table", None),
    ("hsqbench.sim.ik", "ArmIK.solve", None, "IK solve"),
    ("hsqbench.sim.ik", "ArmIK.solve_line", None, "IK solve"),
    ("hsqbench.sim.ik", "ArmIK.sweep_clearance", None, "arm-table/bin sweep check"),
    ("hsqbench.sim.ik", "ArmIK.points_hit", None, "arm-cloud check"),
    ("hsqbench.experiment.results", "ResultStore.append", "results rows", None),
    ("hsqbench.sim.motion", "Stepper.step", None, _phase_physics),
    ("mujoco", "mj_step", None, _physics),
)


class Attribution:
    """Exclusive (wall, CPU) seconds per ``(step, part)`` of the wrapped calls (module doc)."""

    def __init__(self) -> None:
        self.seconds: dict[tuple[str, str], list[float]] = defaultdict(lambda: [0.0, 0.0])
        self._stack: list[tuple[str, str]] = []
        self._mark = self._now()
        self._undo: list[Callable[[], None]] = []

    @staticmethod
    def _now() -> tuple[float, float]:
        return time.perf_counter(), time.process_time()

    def _charge(self) -> None:
        now = self._now()
        where = self._stack[-1] if self._stack else ("other", "")
        acc = self.seconds[where]
        acc[0] += now[0] - self._mark[0]
        acc[1] += now[1] - self._mark[1]
        self._mark = now

    def _wrap(self, fn: Callable[..., Any], step: str | None, part: Part) -> Callable:
        @functools.wraps(fn)
        def wrapper(*args: Any, **kwargs: Any) -> Any:
            self._charge()
            outer_step, outer_part = self._stack[-1] if self._stack else ("other", "")
            name = part(args, outer_part) if callable(part) else part
            self._stack.append((step or outer_step, name or "rest"))
            try:
                return fn(*args, **kwargs)
            finally:
                self._charge()
                self._stack.pop()

        return wrapper

    def install(
        self, wrapped: tuple[tuple[str, str, str | None, Part], ...] = WRAPPED
    ) -> list[str]:
        """Wrap every function of ``wrapped`` that this code version has; returns the ones it
        lacks."""
        missing = []
        for module_name, path, step, part in wrapped:
            try:
                owner: Any = importlib.import_module(module_name)
                *parents, attr = path.split(".")
                for p in parents:
                    owner = getattr(owner, p)
                fn = getattr(owner, attr)
            except (ImportError, AttributeError):
                missing.append(f"{module_name}.{path}")
                continue
            raw = vars(owner).get(attr, fn) if isinstance(owner, type) else fn
            wrapped = self._wrap(fn, step, part)
            # A classmethod looked up on its class is bound already: the wrapper stays plain.
            setattr(owner, attr, wrapped)
            self._undo.append(functools.partial(setattr, owner, attr, raw))
        return missing

    def uninstall(self) -> None:
        for undo in reversed(self._undo):
            undo()
        self._undo = []

    def reset(self) -> None:
        self.seconds.clear()
        self._mark = self._now()

    def table(self, trials: int) -> list[str]:
        """Lines: step, part, wall and CPU seconds per trial, share of the CPU total."""
        self._charge()
        total_cpu = sum(v[1] for v in self.seconds.values()) or 1.0
        steps: dict[str, float] = defaultdict(float)
        for (step, _), (_, cpu) in self.seconds.items():
            steps[step] += cpu
        lines = [f"{'step':18s} {'part':28s} {'wall_s':>7s} {'cpu_s':>7s} {'cpu %':>6s}"]
        for step in sorted(steps, key=lambda s: -steps[s]):
            parts = [(k[1], v) for k, v in self.seconds.items() if k[0] == step]
            for part, (wall, cpu) in sorted(parts, key=lambda kv: -kv[1][1]):
                lines.append(
                    f"{step:18s} {part:28s} {wall / trials:7.3f} {cpu / trials:7.3f} "
                    f"{100 * cpu / total_cpu:6.1f}"
                )
        wall = sum(v[0] for v in self.seconds.values())
        lines.append(f"{'total':47s} {wall / trials:7.3f} {total_cpu / trials:7.3f} {100:6.1f}")
        return lines
