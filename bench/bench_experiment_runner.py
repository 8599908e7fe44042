"""Runner overhead per trial, with a fake backend that does no work (the cost is all ours).

Measures, on the paper protocol (3 planners, 450 isolated trials + 45 packed rounds):
- in-process (``--jobs 1``): seconds per trial of bookkeeping, durable append (fsync) included;
- local pool (``--jobs 2``): seconds per trial including process start-up and IPC;
- the report (tables + three PNG plots) of the whole run.
A real trial takes seconds (the paper: 1-1.5 s to plan alone), so an overhead in milliseconds
is negligible. Run: ``.venv/bin/python bench/bench_experiment_runner.py``.
"""

from __future__ import annotations

import sys
from pathlib import Path as _Path

# The test scaffolding (tests/fake_backend.py, tests/hold_rig.py) lives with the tests.
sys.path.insert(0, str(_Path(__file__).resolve().parents[1]))

import tempfile
import time
import warnings
from pathlib import Path

from hsqbench.experiment.config import load_experiment_config
from hsqbench.experiment.executor import LocalExecutor, SerialExecutor
from hsqbench.experiment.report import write_report
from hsqbench.experiment.runner import run_benchmark
from tests.fake_backend import FakeBackend


def main() -> None:
    config = load_experiment_config("paper")
    with tempfile.TemporaryDirectory() as tmp:
        for name, executor in (("jobs=1", SerialExecutor()), ("jobs=2", LocalExecutor(2))):
            run_dir = Path(tmp) / name
            start = time.perf_counter()
            summary = run_benchmark(
                config, run_dir, backend=FakeBackend(), executor=executor, progress=False
            )
            elapsed = time.perf_counter() - start
            print(
                f"runner {name}: {summary.ran} trials in {elapsed:.2f} s = "
                f"{1e3 * elapsed / summary.ran:.2f} ms per trial (fake backend, no work)"
            )
        start = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)
            written = write_report(Path(tmp) / "jobs=1")
        print(f"report: {len(written)} files in {time.perf_counter() - start:.2f} s")


if __name__ == "__main__":
    main()
