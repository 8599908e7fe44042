"""Executors: the same trials give the same rows in one process, a pool, or on Ray."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
from pathlib import Path

import pytest

from hsqbench.experiment.config import ExperimentConfig, IsolatedConfig, PackedConfig
from hsqbench.experiment.executor import (
    WORKER_DIED,
    LocalExecutor,
    RayExecutor,
    SerialExecutor,
    forwarded_settings,
    make_executor,
)
from hsqbench.experiment.results import VOLATILE_COLUMNS, load_results
from hsqbench.experiment.runner import run_benchmark
from hsqbench.experiment.seeds import build_trials
from tests.fake_backend import FakeBackend

# Trials that take a moment, so the second worker always gets some: with instant trials one
# worker could finish them all before the other has started on a loaded machine.
TRIAL_S = 0.1

CONFIG = ExperimentConfig(
    planners=("a", "b"),
    isolated=IsolatedConfig(objects=("mug", "bowl", "apple", "banana"), attempts_per_object=2),
    packed=PackedConfig(objects=("mug", "bowl", "apple", "banana"), rounds=3, objects_per_round=3),
)


def _rows(run_dir: Path, table: str = "attempts") -> list[tuple]:
    results = load_results(run_dir)
    rows = results.attempts if table == "attempts" else results.rounds
    return sorted(tuple(v for k, v in r.items() if k not in VOLATILE_COLUMNS) for r in rows)


@pytest.fixture(scope="module")
def serial_run(tmp_path_factory) -> Path:
    run_dir = tmp_path_factory.mktemp("serial") / "run"
    backend = FakeBackend(raise_on=("apple",), sleep_s=TRIAL_S)
    run_benchmark(CONFIG, run_dir, backend=backend, executor=SerialExecutor(), progress=False)
    return run_dir


def test_process_pool_gives_the_same_rows_as_one_process(serial_run, tmp_path) -> None:
    run_dir = tmp_path / "pool"
    backend = FakeBackend(raise_on=("apple",), sleep_s=TRIAL_S)
    summary = run_benchmark(
        CONFIG, run_dir, backend=backend, executor=LocalExecutor(jobs=2), progress=False
    )
    assert summary.ran == len(build_trials(CONFIG))
    assert _rows(run_dir) == _rows(serial_run)
    assert _rows(run_dir, "rounds") == _rows(serial_run, "rounds")
    workers = {r["worker"] for r in load_results(run_dir).attempts}
    assert len(workers) == 2  # really two processes
    # A presentation's planners run in one worker, one after another (they share its scene).
    by_presentation: dict[str, set[str]] = {}
    for r in load_results(run_dir).attempts:
        experiment, _planner, rest = r["trial_key"].split("/", 2)
        by_presentation.setdefault(f"{experiment}/{rest}", set()).add(r["worker"])
    assert all(len(w) == 1 for w in by_presentation.values())


def test_a_worker_crash_is_pinned_on_its_trial(tmp_path) -> None:
    config = ExperimentConfig(
        planners=("a",),
        isolated=IsolatedConfig(objects=("mug", "bowl", "apple", "pear", "kiwi"), attempts_per_object=2),
        packed=PackedConfig(enabled=False),
    )  # fmt: skip
    run_dir = tmp_path / "crash"
    backend = FakeBackend(exit_on=("apple",))  # os._exit in the worker: the pool breaks
    summary = run_benchmark(
        config, run_dir, backend=backend, executor=LocalExecutor(jobs=2), progress=False
    )
    results = load_results(run_dir)
    assert len(results.complete_keys) == summary.selected == 10
    errors = {r["trial_key"]: r["detail"] for r in results.attempts if r["status"] == "error"}
    assert set(errors) == {"isolated/a/s0/apple/000", "isolated/a/s0/apple/001"}
    assert all(WORKER_DIED in d for d in errors.values())
    assert summary.errors == 2


def test_make_executor() -> None:
    assert isinstance(make_executor("local", 1), SerialExecutor)
    assert make_executor("local", 3) == LocalExecutor(3)
    with pytest.raises(ValueError, match="unknown executor"):
        make_executor("dask", 2)
    with pytest.raises(ValueError, match="jobs"):
        make_executor("local", 0)


def _ray():
    """Ray, which CI installs (the `ray` extra, in `make install`): there the Ray tests must run,
    so a missing Ray fails them; elsewhere they are skipped without it."""
    if os.environ.get("CI"):
        import ray

        return ray
    return pytest.importorskip("ray", reason="Ray is optional: pip install -e '.[ray]'")


def test_ray_gives_the_same_rows(serial_run, tmp_path) -> None:
    _ray()
    run_dir = tmp_path / "ray"
    backend = FakeBackend(raise_on=("apple",))
    executor = make_executor("ray", 2)  # a private local Ray with 2 CPUs, stopped afterwards
    run_benchmark(CONFIG, run_dir, backend=backend, executor=executor, progress=False)
    assert _rows(run_dir) == _rows(serial_run)
    assert _rows(run_dir, "rounds") == _rows(serial_run, "rounds")
    hosts_pids = {r["worker"] for r in load_results(run_dir).attempts}
    assert len(hosts_pids) >= 2  # Ray worker processes, not this one
    assert f"{socket.gethostname()}:{os.getpid()}" not in hosts_pids


def _setting(name: str) -> str | None:
    return os.environ.get(name)


_CLUSTER = """
import sys, ray
context = ray.init(address="local", num_cpus=2, include_dashboard=False)
print(context.address_info["gcs_address"], flush=True)
sys.stdin.read()  # hold the cluster until the test closes stdin
ray.shutdown()
"""


def test_ray_on_an_existing_cluster_gives_the_same_rows(serial_run, tmp_path, monkeypatch) -> None:
    """--address: join a cluster started elsewhere (here by another process, as `ray start
    --head` would) and forward the settings; the rows are those of one process."""
    _ray()
    holder = subprocess.Popen(
        [sys.executable, "-c", _CLUSTER], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True
    )
    try:
        address = holder.stdout.readline().strip()
        assert address, "the cluster process did not start Ray"
        monkeypatch.setenv("HSQ_YCB_DIR", str(tmp_path))  # forwarded to the workers
        executor = make_executor("ray", None, address)
        assert forwarded_settings()["HSQ_YCB_DIR"] == str(tmp_path)
        ray = _ray()
        executor._init(ray)
        try:
            seen = ray.get(ray.remote(num_cpus=1)(_setting).remote("HSQ_YCB_DIR"))
        finally:
            ray.shutdown()
        assert seen == str(tmp_path)  # the cluster's workers got this process's setting
        run_dir = tmp_path / "cluster"
        backend = FakeBackend(raise_on=("apple",))
        run_benchmark(CONFIG, run_dir, backend=backend, executor=executor, progress=False)
    finally:
        holder.stdin.close()
        holder.wait(timeout=60)
    assert _rows(run_dir) == _rows(serial_run)
    assert _rows(run_dir, "rounds") == _rows(serial_run, "rounds")


def test_ray_executor_arguments() -> None:
    with pytest.raises(ValueError, match="not both"):
        RayExecutor(address="auto", num_cpus=2)
    with pytest.raises(ValueError, match="--executor ray"):
        make_executor("local", 2, "auto")


def test_ray_runs_real_trials_as_one_process_does(tmp_path, monkeypatch) -> None:
    """The simulation backend itself through Ray: the same rows as in this process."""
    _ray()
    monkeypatch.setenv("HSQ_CACHE_DIR", str(tmp_path / "cache"))
    config = ExperimentConfig(
        planners=("hsq",),
        isolated=IsolatedConfig(objects=("proc_box", "proc_cylinder"), attempts_per_object=1),
        packed=PackedConfig(enabled=False),
    )
    run_benchmark(config, tmp_path / "serial", executor=SerialExecutor(), progress=False)
    run_benchmark(config, tmp_path / "ray", executor=make_executor("ray", 2), progress=False)
    serial = load_results(tmp_path / "serial").attempts
    assert serial and all(r["status"] == "ok" for r in serial), [r["detail"] for r in serial]
    assert _rows(tmp_path / "ray") == _rows(tmp_path / "serial")
