"""How the runner runs one trial: a :class:`TrialBackend`, called inside a worker process.

The default backend, :class:`SimBackend`, calls the MuJoCo trial runner
(``hsqbench.sim.trial.run_isolated_trial`` / ``run_packed_round``, the latter also for pile
rounds with ``kind="pile"``), imported lazily in the
worker. Tests inject a fake backend (:mod:`tests.fake_backend`). A backend must be
picklable (it is sent to worker processes) and deterministic for a given trial seed.

:func:`execute_trial` wraps a call: any exception raised by the backend becomes an *error* record
(a harness fault: a scene that could not be built, a worker that died; never a grasp outcome),
so one bad trial cannot stop a run. A planner's own exception never gets here: the trial runner
records it as that planner's ``planner_error`` attempt (:mod:`hsqbench.planner.failure`).
"""

from __future__ import annotations

import importlib
import os
import socket
import time
import traceback
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

from hsqbench.experiment.heap import keep_freed_memory
from hsqbench.experiment.seeds import TrialSpec
from hsqbench.planner.failure import one_line
from hsqbench.sim.outcome import Attempt, Outcome, RoundResult, TrialResult

ERROR_DETAIL_CHARS = 600


class TrialRunnerUnavailable(RuntimeError):
    """The simulation trial runner cannot be imported: nothing can be run."""


@runtime_checkable
class TrialBackend(Protocol):
    """Runs single trials. Implementations must be picklable and deterministic per seed."""

    name: str

    def fingerprint(self) -> dict[str, Any]:
        """Settings that change results (hashed into the run's config hash)."""
        ...

    def check(self, planners: tuple[str, ...]) -> None:
        """Fail early, in the parent, with a clear message when trials cannot run."""
        ...

    def prepare(self, objects: tuple[str, ...], jobs: int | None, progress: bool) -> dict[str, str]:
        """Make ``objects`` ready before any trial (build them, ``jobs`` at a time), in the
        parent. Returns the objects that cannot be used, each with the reason in one line; their
        trials are recorded as errors without running. Raises for a name it does not know."""
        ...

    def placeable(self, objects: tuple[str, ...], seed: int) -> bool:
        """Whether a packed round of ``objects`` with ``seed`` can be set up (its objects placed
        apart). Called in the parent while the trial list is built, so it must be cheap; only
        asked about objects that :meth:`prepare` made ready."""
        ...

    def pile_placeable(self, objects: tuple[str, ...], seed: int) -> bool:
        """Whether a pile round of ``objects`` with ``seed`` gets a pile that settles on the
        table inside the workspace (in the parent, as :meth:`placeable`)."""
        ...

    def run_isolated(self, obj: str, seed: int, planner: str) -> TrialResult: ...

    def run_packed(self, objects: list[str], seed: int, planner: str) -> RoundResult: ...

    def run_pile(self, objects: list[str], seed: int, planner: str) -> RoundResult: ...


@dataclass
class TrialRun:
    """What a worker sends back: the result, or the error that prevented it.

    Attributes:
        wall_s: wall-clock seconds of the whole trial in the worker.
        worker: ``host:pid`` of the process that ran it.
    """

    spec: TrialSpec
    result: TrialResult | RoundResult | None
    error: str | None
    wall_s: float
    worker: str

    @property
    def ok(self) -> bool:
        return self.error is None

    @classmethod
    def failed(cls, spec: TrialSpec, error: str, wall_s: float = float("nan")) -> TrialRun:
        return cls(spec, None, _one_line(error), wall_s, "")


def _one_line(text: str) -> str:
    return one_line(text, ERROR_DETAIL_CHARS)


def _check_result(spec: TrialSpec, result: Any) -> None:
    """The backend must answer the question asked: the right type, trial and attempt records."""
    want = TrialResult if spec.experiment == "isolated" else RoundResult
    if not isinstance(result, want):
        raise TypeError(f"backend returned {type(result).__name__}, expected {want.__name__}")
    if result.seed != spec.seed or result.planner != spec.planner:
        raise ValueError(
            f"backend returned the result of another trial (seed {result.seed}, planner "
            f"{result.planner!r}; expected seed {spec.seed}, planner {spec.planner!r})"
        )
    if isinstance(result, TrialResult):
        got_objects, expected = (result.object,), spec.objects
    else:  # a round presents the draw less the objects its scene could not place
        got_objects = tuple(result.objects)
        expected = tuple(o for o in spec.objects if o not in result.objects_unplaced)
        if not set(result.objects_unplaced) <= set(spec.objects) or not got_objects:
            raise ValueError(
                f"backend returned objects {got_objects} (unplaced {result.objects_unplaced}) "
                f"for the draw {spec.objects}"
            )
    if got_objects != expected:
        raise ValueError(f"backend returned objects {got_objects}, expected {expected}")
    if not result.attempts:
        raise ValueError("backend returned a trial without any attempt")
    for a in result.attempts:
        if not isinstance(a, Attempt) or not isinstance(a.outcome, Outcome):
            raise TypeError(f"attempts must be Attempt records with an Outcome, got {a!r}")
    if isinstance(result, RoundResult):
        out = [*result.objects_cleared, *result.objects_lost]
        if not set(out) <= set(result.objects) or len(set(out)) != len(out):
            raise ValueError(
                f"objects_cleared {result.objects_cleared} and objects_lost "
                f"{result.objects_lost} must be distinct objects of the round"
            )


def execute_trial(backend: TrialBackend, spec: TrialSpec) -> TrialRun:
    """Run one trial in this process; exceptions become an error record (KeyboardInterrupt and
    SystemExit propagate so that a run can still be stopped)."""
    worker = f"{socket.gethostname()}:{os.getpid()}"
    start = time.perf_counter()
    try:
        if spec.experiment == "isolated":
            result = backend.run_isolated(spec.objects[0], spec.seed, spec.planner)
        elif spec.experiment == "pile":
            result = backend.run_pile(list(spec.objects), spec.seed, spec.planner)
        else:
            result = backend.run_packed(list(spec.objects), spec.seed, spec.planner)
        _check_result(spec, result)
    except Exception as exc:
        frames = traceback.extract_tb(exc.__traceback__)
        where = f" (at {frames[-1].filename}:{frames[-1].lineno})" if frames else ""
        error = f"{type(exc).__name__}: {exc}{where}"
        return TrialRun(spec, None, _one_line(error), time.perf_counter() - start, worker)
    return TrialRun(spec, result, None, time.perf_counter() - start, worker)


def presentation_groups(specs: Sequence[TrialSpec]) -> list[list[TrialSpec]]:
    """The specs as runs of one presentation each: consecutive specs that differ only in the
    planner (the trial list puts a presentation's planners side by side), in order."""
    groups: list[list[TrialSpec]] = []
    for spec in specs:
        if groups and _presentation(groups[-1][0]) == _presentation(spec):
            groups[-1].append(spec)
        else:
            groups.append([spec])
    return groups


def _presentation(spec: TrialSpec) -> tuple:
    return (spec.experiment, spec.base_seed, spec.index, spec.objects, spec.seed)


def execute_group(backend: TrialBackend, specs: Sequence[TrialSpec]) -> list[TrialRun]:
    """:func:`execute_trial` for each spec of one presentation, in one worker: its planners
    then share the scene, the first look and the graspability search
    (:mod:`hsqbench.sim.trial.presentation`)."""
    return [execute_trial(backend, s) for s in specs]


@dataclass
class SimBackend:
    """The MuJoCo trial runner of ``hsqbench.sim.trial``.

    The trial module must provide ``TrialConfig`` (a config dataclass),
    ``run_isolated_trial(object, seed, planner, config)`` and
    ``run_packed_round(objects, seed, planner, config)``; ``load_trial_config(name, overrides)``
    and ``named_inputs(config)`` where it has them. The config tree is loaded once per process
    and handed whole to every trial.
    """

    trial_config: str = "trial"
    name: str = "sim"
    #: ``(dotted.path, value)`` pairs applied to the trial config tree's data before it is
    #: built (``hsqbench.sim.trial.load_trial_config``), e.g. for a parameter sweep.
    overrides: tuple[tuple[str, Any], ...] = ()

    def __post_init__(self) -> None:
        self._config: Any = None
        self._specs: tuple[tuple[str, str], ...] | None = None

    def __getstate__(self) -> dict[str, Any]:
        from hsqbench.planner.registry import specs_of

        return {
            "trial_config": self.trial_config,
            "name": self.name,
            "overrides": self.overrides,
            # Planners plugged in from a spec (a file, a module) travel to the workers, which
            # register them again (entry points they find themselves).
            "plugin_specs": specs_of(),
        }

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.trial_config = state["trial_config"]
        self.name = state["name"]
        self.overrides = tuple(state.get("overrides", ()))
        self._config = None
        self._specs = tuple(state.get("plugin_specs", ()))

    def _register_plugins(self) -> None:
        """In a worker: register the run's planners plugged in from specs (once)."""
        if self._specs:
            from hsqbench.planner.registry import register_specs

            register_specs(self._specs)
            self._specs = ()

    @staticmethod
    def _module() -> Any:
        # import_module consults sys.modules first; `from hsqbench.sim import trial` would return
        # the package attribute even when the module entry has been replaced or removed.
        try:
            trial = importlib.import_module("hsqbench.sim.trial")
        except ImportError as exc:
            raise TrialRunnerUnavailable(
                "the simulation trial runner (hsqbench.sim.trial) is not available "
                f"({type(exc).__name__}: {exc}); no trial was run"
            ) from exc
        missing = [
            n
            for n in ("TrialConfig", "run_isolated_trial", "run_packed_round")
            if not hasattr(trial, n)
        ]
        if missing:
            raise TrialRunnerUnavailable(
                f"hsqbench.sim.trial lacks {missing}: the trial runner is not complete; "
                "no trial was run"
            )
        return trial

    def _trial_config(self) -> Any:
        if self._config is None:
            keep_freed_memory()  # the process runs trials from now on (hsqbench.experiment.heap)
            trial = self._module()
            load = getattr(trial, "load_trial_config", None)
            if load is None:  # a minimal trial module: its TrialConfig from the file as is
                from hsqbench.config import load_tree

                self._config = load_tree(
                    trial.TrialConfig, self.trial_config, dict(self.overrides) or None
                )
            else:
                self._config = load(self.trial_config, dict(self.overrides) or None)
        return self._config

    def fingerprint(self) -> dict[str, Any]:
        """The resolved trial config tree (every config a trial reads, loaded once: scene,
        robot, physics, perception, each planner's, the oracle's, the object library's) and
        the files it names below config level (``named_inputs``), so editing any of them
        changes the run's config hash and a resume cannot mix results of different settings."""
        from hsqbench.config import to_dict

        tc = self._trial_config()
        out: dict[str, Any] = {"backend": self.name, "trial_config": to_dict(tc)}
        named = getattr(self._module(), "named_inputs", None)
        if named is not None:
            out["named_inputs"] = named(tc)
        if self.overrides:  # already in the tree; named too, so run.json says what a point set
            out["overrides"] = dict(self.overrides)
        return out

    def check(self, planners: tuple[str, ...]) -> None:
        self._trial_config()
        try:
            from hsqbench.planner.registry import planner_names
        except ImportError:
            return  # the trial runner resolves names itself and reports unknown ones per trial
        known = set(planner_names())
        unknown = [p for p in planners if p not in known]
        if unknown:
            raise ValueError(f"unknown planner(s) {unknown}; known: {sorted(known)}")
        from hsqbench.planner.registry import get_planner, is_builtin, unavailable

        for p in planners:
            why = unavailable(p)
            if why is not None:
                raise ValueError(f"planner {p!r} cannot run: {why}")
        tc = self._trial_config()
        for p in planners:
            if not is_builtin(p):  # a plugin that cannot be built says so once, before any trial
                get_planner(p, tc.planners.for_planner(p))

    def prepare(self, objects: tuple[str, ...], jobs: int | None, progress: bool) -> dict[str, str]:
        """Download the YCB ones missing from the download folder (only when ``HSQ_YCB_DIR`` is
        unset), then build (or load from the cache) exactly these objects of the library."""
        from hsqbench.assets.library import prepare_objects
        from hsqbench.assets.on_demand import fetch_missing

        fetch_missing(objects, progress=progress)
        return prepare_objects(objects, jobs=jobs, progress=progress).failed

    def placeable(self, objects: tuple[str, ...], seed: int) -> bool:
        """The scene builder's own placement with the trial config's scene, without a model."""
        from hsqbench.sim.scene import packed_placeable

        tc = self._trial_config()
        if getattr(tc, "clutter", None) is not None:
            return True  # VGN/GIGA's rounds start with what their generation places
        return packed_placeable(objects, seed, tc.scene)

    def pile_placeable(self, objects: tuple[str, ...], seed: int) -> bool:
        """The scene builder's own pile drop and checks (a second or two; remembered, so the
        round's trials in this process reuse it) with the trial config's scene, robot, physics."""
        from hsqbench.sim.scene import pile_placeable

        tc = self._trial_config()
        if getattr(tc, "clutter", None) is not None:
            return True  # as placeable
        return pile_placeable(objects, seed, tc.scene, tc.physics, tc.robot)

    def run_isolated(self, obj: str, seed: int, planner: str) -> TrialResult:
        self._register_plugins()
        return self._module().run_isolated_trial(obj, seed, planner, self._trial_config())

    def run_packed(self, objects: list[str], seed: int, planner: str) -> RoundResult:
        self._register_plugins()
        return self._module().run_packed_round(objects, seed, planner, self._trial_config())

    def run_pile(self, objects: list[str], seed: int, planner: str) -> RoundResult:
        self._register_plugins()
        return self._module().run_packed_round(
            objects, seed, planner, self._trial_config(), kind="pile"
        )
