"""A benchmark killed with SIGKILL leaves no process behind: workers, fork server, tracker."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from hsqbench.experiment import lifeline

REPO = Path(__file__).resolve().parents[1]

# Two workers in trials that would sleep a minute: what a killed `benchmark --jobs 2` leaves.
_RUN = """
import sys
from hsqbench.experiment.config import ExperimentConfig, IsolatedConfig
from hsqbench.experiment.executor import LocalExecutor
from hsqbench.experiment.runner import run_benchmark
from tests.fake_backend import FakeBackend

config = ExperimentConfig(
    planners=("a",), isolated=IsolatedConfig(objects=("mug", "bowl", "apple"), attempts_per_object=2)
)
run_benchmark(config, sys.argv[1], backend=FakeBackend(sleep_s=60), executor=LocalExecutor(jobs=2),
              progress=False)
"""


def _processes() -> dict[int, tuple[int, str]]:
    """pid -> (parent pid, start time in clock ticks) of every process."""
    out = {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            stat = Path(f"/proc/{entry}/stat").read_text()
        except OSError:
            continue
        fields = stat[stat.rindex(")") + 2 :].split()
        out[int(entry)] = (int(fields[1]), fields[19])
    return out


def _descendants(root: int) -> dict[int, str]:
    """pid -> start time of every descendant of ``root`` (the start time tells a reused pid)."""
    procs = _processes()
    found, frontier = {}, [root]
    while frontier:
        parent = frontier.pop()
        for pid, (ppid, start) in procs.items():
            if ppid == parent and pid not in found:
                found[pid] = start
                frontier.append(pid)
    return found


def _still_there(procs: dict[int, str]) -> list[int]:
    now = _processes()
    return [pid for pid, start in procs.items() if pid in now and now[pid][1] == start]


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads /proc (Linux)")
def test_a_killed_benchmark_leaves_no_process(tmp_path) -> None:
    proc = subprocess.Popen(
        [sys.executable, "-c", _RUN, str(tmp_path / "run")],
        cwd=REPO,
        env={**os.environ, "PYTHONPATH": str(REPO)},
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )
    try:
        deadline = time.monotonic() + 60
        children: dict[int, str] = {}
        # The tracker, the fork server and its two workers (grandchildren of the parent).
        while time.monotonic() < deadline and proc.poll() is None:
            children = _descendants(proc.pid)
            grandchildren = [p for p, (pp, _) in _processes().items() if pp in children]
            if len(children) >= 2 and len(grandchildren) >= 2:
                break
            time.sleep(0.1)
        else:
            pytest.fail(f"the pool did not start: {proc.stderr.read().decode()[-2000:]}")
        children = _descendants(proc.pid)
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        deadline = time.monotonic() + 10
        while _still_there(children) and time.monotonic() < deadline:
            time.sleep(0.1)
        left = _still_there(children)
        for pid in left:  # not to leave them behind when the check fails
            os.kill(pid, signal.SIGKILL)
        assert not left, f"{len(left)} of {len(children)} processes outlived their killed parent"
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def test_exit_with_an_ended_process_ends_this_one() -> None:
    """The watch also works on a parent that is already gone (a pidfd cannot be opened)."""
    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()
    code = (
        "import sys; from hsqbench.experiment.lifeline import exit_with; "
        f"exit_with({gone.pid}); import time; time.sleep(30)"
    )
    start = time.monotonic()
    done = subprocess.run(
        [sys.executable, "-c", code], cwd=REPO, env={**os.environ, "PYTHONPATH": str(REPO)}
    )
    assert done.returncode == 1 and time.monotonic() - start < 20


def test_the_fork_server_watches_only_the_parent_named() -> None:
    assert lifeline.PARENT_ENV == "HSQBENCH_POOL_PARENT"
    env = {**os.environ, "PYTHONPATH": str(REPO), lifeline.PARENT_ENV: "1"}  # not our parent
    code = "import hsqbench.experiment.lifeline as l; print(sorted(l._watched))"
    out = subprocess.run(
        [sys.executable, "-c", code], cwd=REPO, env=env, capture_output=True, text=True
    )
    assert out.stdout.strip() == "[]"
    env[lifeline.PARENT_ENV] = str(os.getpid())  # the subprocess's parent: watched
    out = subprocess.run(
        [sys.executable, "-c", code], cwd=REPO, env=env, capture_output=True, text=True
    )
    assert out.stdout.strip() == f"[{os.getpid()}]"
