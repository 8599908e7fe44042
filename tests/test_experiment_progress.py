"""Progress in a log file: plain lines every N trials or seconds, with the running GSR and ETA."""

from __future__ import annotations

import io

from hsqbench.experiment.config import ExperimentConfig, IsolatedConfig, PackedConfig
from hsqbench.experiment.progress import RunProgress, Tally, format_duration
from hsqbench.experiment.runner import run_benchmark
from tests.fake_backend import FakeBackend


class _Clock:
    def __init__(self) -> None:
        self.t = 100.0

    def __call__(self) -> float:
        return self.t


def _row(planner: str, success: bool, status: str = "ok") -> dict[str, str]:
    return {"planner": planner, "success": "1" if success else "0", "status": status}


def test_durations() -> None:
    assert format_duration(12.4) == "12s"
    assert format_duration(245) == "4m05s"
    assert format_duration(3720) == "1h02m"


def test_plain_lines_every_n_trials_with_gsr_and_eta() -> None:
    out, clock, tally = io.StringIO(), _Clock(), Tally()
    shown = RunProgress("run", 10, 2, tally, out, every_trials=3, every_s=1e9, clock=clock)
    for i in range(8):
        clock.t += 2.0  # 2 s per trial
        tally.add([_row("hsq", i % 4 != 0)])
        shown.update()
    shown.close()
    lines = out.getvalue().splitlines()
    assert "\r" not in out.getvalue()
    # start, after 3 and 6 trials of this session, and the last one at the end
    assert [line.split(": ")[1].split(" trials")[0] for line in lines] == [
        "2/10",
        "5/10",
        "8/10",
        "10/10",
    ]
    assert "GSR hsq 66.7% (2/3)" in lines[1]
    assert "ETA 10s" in lines[1]  # 5 left at 2 s each
    assert lines[-1].endswith("done") and "GSR hsq 75.0% (6/8)" in lines[-1]
    assert "ETA unknown" in lines[0]


def test_plain_lines_every_s_seconds_and_errors_counted() -> None:
    out, clock, tally = io.StringIO(), _Clock(), Tally()
    shown = RunProgress("run", 100, 0, tally, out, every_trials=1000, every_s=30.0, clock=clock)
    for _ in range(4):
        clock.t += 20.0
        tally.add([_row("a", True, status="error")])
        shown.update()
    lines = out.getvalue().splitlines()
    assert len(lines) == 3  # start, at 40 s, at 80 s
    assert "2 errors" in lines[1] and "elapsed 40s" in lines[1]


def test_a_run_into_a_file_logs_lines_not_a_bar(tmp_path, capsys) -> None:
    config = ExperimentConfig(
        planners=("a", "b"),
        isolated=IsolatedConfig(objects=("mug", "bowl"), attempts_per_object=2),
        packed=PackedConfig(enabled=False),
    )
    run_benchmark(config, tmp_path / "r", backend=FakeBackend())
    err = capsys.readouterr().err
    assert "\r" not in err
    lines = [line for line in err.splitlines() if " trials (" in line]
    assert lines[0].startswith("r: 0/8 trials") and lines[-1].startswith("r: 8/8 trials (100 %)")
    assert "GSR a " in lines[-1] and "GSR" in lines[-1] and ", b " in lines[-1]
