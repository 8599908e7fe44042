"""Where trials run: in this process, in a local process pool, or on a Ray cluster.

Every executor yields one :class:`~hsqbench.experiment.backend.TrialRun` per trial, in the order
trials finish; the parent process alone writes results. A trial is a pure function of
(backend, spec), so all executors give the same records for the same seeds.

The pool and Ray executors hand a worker one *presentation* at a time: the trials that differ
only in the planner (:func:`~hsqbench.experiment.backend.presentation_groups`), run one after
another in that worker, so they share the scene and the first look
(:mod:`hsqbench.sim.trial.presentation`); the serial executor runs them in the same order.

A worker process that dies (segfault in native code, out of memory, ``os._exit``) breaks a
``ProcessPoolExecutor``, and the pool cannot say which trial did it. The local executor then
re-runs the presentations that may have been in flight (at most ``2 * jobs + 1``, the earliest
unfinished ones: the pool feeds ``jobs + 1`` queued calls in submission order) one trial at a
time in fresh single-worker pools; the trial that kills its worker again is recorded as an
error, the others complete normally, and the rest of the run goes on in a fresh pool.
"""

from __future__ import annotations

import contextlib
import importlib.machinery
import multiprocessing
import os
import sys
from collections.abc import Iterator, Sequence
from concurrent.futures import Future, ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from typing import Any, Protocol

from hsqbench.experiment import lifeline
from hsqbench.experiment.backend import (
    TrialBackend,
    TrialRun,
    execute_group,
    execute_trial,
    presentation_groups,
)
from hsqbench.experiment.seeds import TrialSpec

EXECUTORS = ("local", "ray")
WORKER_DIED = (
    "the worker process died while running this trial (a crash in native code, out of memory "
    "or os._exit); it was re-run alone and died again"
)


class Executor(Protocol):
    name: str

    def run(self, backend: TrialBackend, specs: Sequence[TrialSpec]) -> Iterator[TrialRun]:
        """Run every spec once; yield each result as it finishes."""
        ...


@dataclass
class SerialExecutor:
    """Trials one after another in this process (``--jobs 1``: simplest to debug)."""

    name: str = "serial"

    def run(self, backend: TrialBackend, specs: Sequence[TrialSpec]) -> Iterator[TrialRun]:
        for spec in specs:
            yield execute_trial(backend, spec)


def _mp_context() -> multiprocessing.context.BaseContext:
    # The fork server (and any child importing lifeline) ends with this process: see lifeline.
    os.environ[lifeline.PARENT_ENV] = str(os.getpid())
    # Not fork: the parent runs a progress thread, and forking a threaded process can deadlock.
    if "forkserver" not in multiprocessing.get_all_start_methods():
        return multiprocessing.get_context("spawn")
    ctx = multiprocessing.get_context("forkserver")
    # Workers fork from a server that has already imported the trial code and the planners'
    # heavy imports (scikit-learn, SciPy): cheap fresh pools.
    ctx.set_forkserver_preload(
        [
            "hsqbench.experiment.lifeline",
            "hsqbench.experiment.backend",
            "hsqbench.sim.trial",
            "hsqbench.planner.hsq.stage_one.recovery",
        ]
    )
    return ctx


@contextlib.contextmanager
def _main_not_reimported() -> Iterator[None]:
    """While workers start, a script run as ``python script.py`` is not run again in each of
    them (spawn and forkserver import the main module unless it has a name: a script without an
    ``if __name__ == "__main__"`` guard would start a benchmark in every worker). The workers
    need nothing from it: the backend and the plugin planners' specs travel with each trial."""
    main = sys.modules.get("__main__")
    if main is None or getattr(main, "__spec__", None) is not None:
        yield  # `python -m module` (imported by name, guarded as a module), or an interpreter
        return
    main.__spec__ = importlib.machinery.ModuleSpec("__main__", None)
    try:
        yield
    finally:
        main.__spec__ = None


def _stop_pool(pool: ProcessPoolExecutor, clean: bool) -> None:
    if clean:
        pool.shutdown(wait=True, cancel_futures=True)
        return
    # Interrupted: do not wait for running trials.
    terminate = getattr(pool, "terminate_workers", None)  # Python >= 3.14
    if terminate is not None:
        terminate()
    else:
        for proc in list(getattr(pool, "_processes", {}).values()):
            proc.terminate()
    pool.shutdown(wait=False, cancel_futures=True)


@dataclass
class LocalExecutor:
    """A pool of ``jobs`` worker processes on this machine."""

    jobs: int
    name: str = "local"

    def __post_init__(self) -> None:
        if self.jobs < 1:
            raise ValueError(f"jobs must be >= 1, got {self.jobs}")

    def _pass(
        self,
        backend: TrialBackend,
        groups: Sequence[list[TrialSpec]],
        workers: int,
        broken: list[list[TrialSpec]],
    ) -> Iterator[TrialRun]:
        """Run ``groups`` (one presentation each) in one pool; groups lost to a broken pool
        are appended to ``broken``."""
        pool = ProcessPoolExecutor(
            max_workers=min(workers, len(groups)),
            mp_context=_mp_context(),
            initializer=lifeline.exit_with,  # a worker ends with this process, even a killed one
            initargs=(os.getpid(),),
        )
        clean = False
        try:
            with _main_not_reimported():  # the workers start as groups are submitted
                futures: dict[Future[list[TrialRun]], list[TrialSpec]] = {
                    pool.submit(execute_group, backend, g): g for g in groups
                }
            lost: set[int] = set()
            for fut in as_completed(futures):
                group = futures[fut]
                try:
                    runs = fut.result()
                except BrokenProcessPool:
                    lost.add(id(group))
                    continue
                except Exception as exc:  # e.g. a result that cannot be pickled
                    runs = [TrialRun.failed(s, f"{type(exc).__name__}: {exc}") for s in group]
                yield from runs
            broken.extend(g for g in futures.values() if id(g) in lost)  # submission order
            clean = True
        finally:
            _stop_pool(pool, clean)

    def run(self, backend: TrialBackend, specs: Sequence[TrialSpec]) -> Iterator[TrialRun]:
        queue = presentation_groups(specs)
        while queue:
            lost: list[list[TrialSpec]] = []
            yield from self._pass(backend, queue, self.jobs, lost)
            if not lost:
                return
            n_suspects = 2 * self.jobs + 1
            suspects, queue = lost[:n_suspects], lost[n_suspects:]
            for spec in (s for group in suspects for s in group):
                again: list[list[TrialSpec]] = []
                yield from self._pass(backend, [[spec]], 1, again)
                if again:
                    yield TrialRun.failed(spec, WORKER_DIED)


# Settings a trial reads from the environment: forwarded to the workers of a Ray cluster (its
# nodes must see the same paths, e.g. on a shared file system).
FORWARDED_SETTINGS = (
    "HSQ_YCB_DIR",
    "HSQ_CACHE_DIR",
    "MENAGERIE_ROOT",
    "MUJOCO_GL",
    "PYOPENGL_PLATFORM",
    "OMP_NUM_THREADS",
)


def forwarded_settings() -> dict[str, str]:
    """The settings of :data:`FORWARDED_SETTINGS` that are set here."""
    return {k: os.environ[k] for k in FORWARDED_SETTINGS if k in os.environ}


@dataclass
class RayExecutor:
    """The same trials as Ray tasks, one CPU each (``pip install -e .[ray]``).

    With ``address`` (``auto``, ``HOST:PORT`` of ``ray start --head``, or ``ray://HOST:PORT``)
    it joins that cluster and forwards this process's settings (:data:`FORWARDED_SETTINGS`) to
    the workers, whose nodes need hsqbench installed and the same paths. Without, it starts a
    private local Ray with ``num_cpus`` CPUs (never joining a Ray someone else runs here).
    Either way it disconnects afterwards; a Ray already initialised in this process is used as
    it is.
    """

    address: str | None = None
    num_cpus: int | None = None
    name: str = "ray"

    def __post_init__(self) -> None:
        if self.address is not None and self.num_cpus is not None:
            raise ValueError(
                "a Ray cluster has its own CPUs: give --address or --jobs with --executor ray, "
                "not both"
            )

    def _init(self, ray: Any) -> None:
        if self.address is None:
            ray.init(
                address="local",
                num_cpus=self.num_cpus,
                include_dashboard=False,
                log_to_driver=False,
            )
            return
        _use_token_auth_if_available()
        try:
            ray.init(
                address=self.address,
                runtime_env={"env_vars": forwarded_settings()},
                log_to_driver=False,
            )
        except ConnectionError as exc:
            raise RuntimeError(
                f"cannot reach a Ray cluster at {self.address!r} ({exc}); start one with "
                "`ray start --head` and pass the address it prints (or 'auto' on its head node)"
            ) from exc

    def run(self, backend: TrialBackend, specs: Sequence[TrialSpec]) -> Iterator[TrialRun]:
        ray = import_ray()
        started = False
        if not ray.is_initialized():
            self._init(ray)
            started = True
        pending: list[Any] = []
        try:
            task = ray.remote(max_retries=0, num_cpus=1)(execute_group)
            backend_ref = ray.put(backend)
            refs = {task.remote(backend_ref, g): g for g in presentation_groups(specs)}
            pending = list(refs)
            while pending:
                done, pending = ray.wait(pending, num_returns=1)
                for ref in done:
                    try:
                        runs = ray.get(ref)
                    except ray.exceptions.RayError as exc:  # worker died, task error, ...
                        runs = [
                            TrialRun.failed(s, f"{type(exc).__name__}: {exc}") for s in refs[ref]
                        ]
                    yield from runs
        finally:
            for ref in pending:
                ray.cancel(ref, force=True)
            if started:
                ray.shutdown()


def _use_token_auth_if_available() -> None:
    """Ray turns on token authentication by itself for ``address=None`` or ``"auto"`` when a
    token exists (a cluster started by ``ray start --head`` or ``ray.init`` writes one), but not
    for an explicit address, where the connection then fails with ``InvalidAuthToken``; do the
    same for every address (``RAY_AUTH_MODE``, when set, is the user's explicit choice)."""
    try:  # Ray's own step (it also refreshes Ray's cached config, which reads the mode once)
        from ray._private.authentication.authentication_token_setup import (
            maybe_enable_token_auth_if_token_available,
        )
    except ImportError:  # a Ray without token authentication
        return
    maybe_enable_token_auth_if_token_available(warn_if_disabled=False)


def import_ray() -> Any:
    try:
        import ray
    except ImportError as exc:
        raise RuntimeError(
            "--executor ray needs Ray: pip install -e '.[ray]' (or .venv/bin/pip install ray)"
        ) from exc
    return ray


def default_jobs() -> int:
    """The number of cores this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:
        return max(1, os.cpu_count() or 1)


def make_executor(
    kind: str = "local", jobs: int | None = None, address: str | None = None
) -> Executor:
    """``local`` with ``jobs`` workers (1: in this process), or ``ray``: a private local Ray of
    ``jobs`` CPUs, or the cluster at ``address``."""
    if kind not in EXECUTORS:
        raise ValueError(f"unknown executor {kind!r}; choose from {list(EXECUTORS)}")
    if jobs is not None and jobs < 1:
        raise ValueError(f"--jobs must be >= 1, got {jobs}")
    if address is not None and kind != "ray":
        raise ValueError("--address is the address of a Ray cluster: use it with --executor ray")
    if kind == "ray":
        import_ray()
        return RayExecutor(address=address, num_cpus=jobs)
    jobs = jobs or default_jobs()
    return SerialExecutor() if jobs == 1 else LocalExecutor(jobs)
