"""Where trials run: in this process, in a local process pool, or on a Ray cluster.

Every executor yields one :class:`~hsqbench.experiment.backend.TrialRun` per trial, in the order
trials finish; the parent process alone writes results. A trial is a pure function of
(backend, spec), so all executors give the same records for the same seeds.

A worker process that dies (segfault in native code, out of memory, ``os._exit``) breaks a
``ProcessPoolExecutor``, and the pool cannot say which trial did it. The local executor then
re-runs the trials that may have been in flight (at most ``2 * jobs + 1``, the earliest
unfinished ones: the pool feeds ``jobs + 1`` queued calls in submission order) one at a time in
fresh single-worker pools; the trial that kills its worker again is recorded as an error, the
others complete normally, and the rest of the run goes on in a fresh pool.
"""

from __future__ import annotations

import multiprocessing
import os
from collections.abc import Iterator, Sequence
from concurrent.futures import Future, ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from typing import Any, Protocol

from hsqbench.experiment.backend import TrialBackend, TrialRun, execute_trial
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
    # Not fork: the parent runs a progress thread, and forking a threaded process can deadlock.
    if "forkserver" not in multiprocessing.get_all_start_methods():
        return multiprocessing.get_context("spawn")
    ctx = multiprocessing.get_context("forkserver")
    # Workers fork from a server that has already imported the trial code: cheap fresh pools.
    ctx.set_forkserver_preload(["hsqbench.experiment.backend"])
    return ctx


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
        self, backend: TrialBackend, specs: Sequence[TrialSpec], workers: int, broken: list[Any]
    ) -> Iterator[TrialRun]:
        """Run ``specs`` in one pool; specs lost to a broken pool are appended to ``broken``."""
        pool = ProcessPoolExecutor(max_workers=min(workers, len(specs)), mp_context=_mp_context())
        clean = False
        try:
            futures: dict[Future[TrialRun], TrialSpec] = {
                pool.submit(execute_trial, backend, s): s for s in specs
            }
            lost: set[str] = set()
            for fut in as_completed(futures):
                spec = futures[fut]
                try:
                    run = fut.result()
                except BrokenProcessPool:
                    lost.add(spec.key)
                    continue
                except Exception as exc:  # e.g. a result that cannot be pickled
                    run = TrialRun.failed(spec, f"{type(exc).__name__}: {exc}")
                yield run
            broken.extend(s for s in futures.values() if s.key in lost)  # submission order
            clean = True
        finally:
            _stop_pool(pool, clean)

    def run(self, backend: TrialBackend, specs: Sequence[TrialSpec]) -> Iterator[TrialRun]:
        queue = list(specs)
        while queue:
            lost: list[TrialSpec] = []
            yield from self._pass(backend, queue, self.jobs, lost)
            if not lost:
                return
            n_suspects = 2 * self.jobs + 1
            suspects, queue = lost[:n_suspects], lost[n_suspects:]
            for spec in suspects:
                again: list[TrialSpec] = []
                yield from self._pass(backend, [spec], 1, again)
                if again:
                    yield TrialRun.failed(spec, WORKER_DIED)


@dataclass
class RayExecutor:
    """The same trials as Ray tasks (``pip install -e .[ray]``).

    Uses the running Ray instance, or starts one with ``ray.init(address, num_cpus)`` and stops
    it afterwards. A remote cluster's workers need hsqbench installed and the same settings
    (``HSQ_YCB_DIR`` ...) in their environment (Ray ``runtime_env``).
    """

    address: str | None = None
    num_cpus: int | None = None
    name: str = "ray"

    def run(self, backend: TrialBackend, specs: Sequence[TrialSpec]) -> Iterator[TrialRun]:
        ray = import_ray()
        started = False
        if not ray.is_initialized():
            ray.init(
                address=self.address,
                num_cpus=self.num_cpus,
                include_dashboard=False,
                log_to_driver=False,
            )
            started = True
        pending: list[Any] = []
        try:
            task = ray.remote(max_retries=0, num_cpus=1)(execute_trial)
            backend_ref = ray.put(backend)
            refs = {task.remote(backend_ref, s): s for s in specs}
            pending = list(refs)
            while pending:
                done, pending = ray.wait(pending, num_returns=1)
                for ref in done:
                    try:
                        run = ray.get(ref)
                    except ray.exceptions.RayError as exc:  # worker died, task error, ...
                        run = TrialRun.failed(refs[ref], f"{type(exc).__name__}: {exc}")
                    yield run
        finally:
            for ref in pending:
                ray.cancel(ref, force=True)
            if started:
                ray.shutdown()


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


def make_executor(kind: str = "local", jobs: int | None = None) -> Executor:
    """``local`` with ``jobs`` workers (1: in this process), or ``ray`` (``jobs`` CPUs if it starts
    Ray itself)."""
    if kind not in EXECUTORS:
        raise ValueError(f"unknown executor {kind!r}; choose from {list(EXECUTORS)}")
    if jobs is not None and jobs < 1:
        raise ValueError(f"--jobs must be >= 1, got {jobs}")
    if kind == "ray":
        import_ray()
        return RayExecutor(num_cpus=jobs)
    jobs = jobs or default_jobs()
    return SerialExecutor() if jobs == 1 else LocalExecutor(jobs)
