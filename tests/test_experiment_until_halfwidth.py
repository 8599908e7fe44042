"""``benchmark --until-halfwidth``: seeds are added until every GSR interval is narrow enough."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from hsqbench.experiment.config import ExperimentConfig, IsolatedConfig, PackedConfig
from hsqbench.experiment.report import load_run, write_report
from hsqbench.experiment.runner import run_benchmark
from hsqbench.experiment.stats import Rate
from hsqbench.experiment.until_halfwidth import run_until_halfwidth, seed_sequence
from tests.fake_backend import FakeBackend

CONFIG = ExperimentConfig(
    planners=("hsq", "antipodal"),
    seeds=(5,),
    isolated=IsolatedConfig(objects=("mug", "bowl", "apple"), attempts_per_object=10),
    packed=PackedConfig(enabled=False),
)


def test_seed_sequence_keeps_the_protocols_seeds_first() -> None:
    assert seed_sequence((3, 1), 5) == (3, 1, 0, 2, 4)
    assert seed_sequence((0, 1, 2), 3) == (0, 1, 2)
    with pytest.raises(ValueError, match="--max-seeds 1: the protocol already has 2 seeds"):
        seed_sequence((0, 1), 1)


def _widest(run_dir: Path, seeds: set[int]) -> float:
    """The widest GSR half-width over the attempts of ``seeds``, from the run's files."""
    attempts = load_run(run_dir).attempts
    widths = []
    for _, g in attempts[attempts["base_seed"].isin(seeds)].groupby("planner"):
        rate = Rate.of(int(g["success"].sum()), len(g))
        widths.append((rate.high - rate.low) / 2)
    return max(widths)


def _steps(tmp_path: Path, target: float, max_seeds: int) -> tuple[Path, list, dict]:
    run_dir = tmp_path / "run"
    backend = FakeBackend(success={"hsq": 0.9, "antipodal": 0.5})
    steps: list[tuple[int, ...]] = []

    def run_seeds(cfg, base_seeds, resume):
        steps.append(tuple(base_seeds))
        return run_benchmark(cfg, run_dir, backend=backend, resume=resume, progress=False,
                             base_seeds=base_seeds)  # fmt: skip

    run_until_halfwidth(CONFIG, run_dir, target, max_seeds, run_seeds)
    return run_dir, steps, json.loads((run_dir / "run.json").read_text())


def test_adds_seeds_until_every_interval_is_narrow_enough(tmp_path: Path) -> None:
    run_dir, steps, meta = _steps(tmp_path, target=0.12, max_seeds=8)
    seeds = steps[-1]
    assert [len(s) for s in steps] == list(range(1, len(steps) + 1)) and steps[0] == (5,)
    assert 1 < len(seeds) < 8
    assert _widest(run_dir, set(seeds)) <= 0.12 < _widest(run_dir, set(seeds[:-1]))
    record = meta["until_halfwidth"]
    assert record["seeds_run"] == list(seeds) and record["reached"] is True
    assert record["target_halfwidth"] == 0.12 and record["max_seeds"] == 8
    assert meta["config"]["seeds"] == list(seed_sequence((5,), 8))  # the hash covers the cap
    assert set(load_run(run_dir).attempts["base_seed"]) == set(seeds)


def test_stops_at_the_seed_cap_and_says_the_target_was_missed(tmp_path: Path) -> None:
    _, steps, meta = _steps(tmp_path, target=0.01, max_seeds=2)
    assert steps == [(5,), (5, 0)]
    assert meta["until_halfwidth"]["reached"] is False
    assert max(meta["until_halfwidth"]["halfwidths"].values()) > 0.01


def test_a_target_outside_zero_to_half_is_an_error(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="--until-halfwidth 2"):
        run_until_halfwidth(CONFIG, tmp_path, 2, 5, lambda *a: None)


def test_the_report_names_the_seeds_that_ran_and_why(tmp_path: Path) -> None:
    run_dir, _, _ = _steps(tmp_path, target=0.01, max_seeds=2)
    write_report(run_dir)
    md = (run_dir / "tables.md").read_text()
    assert "base seeds [5, 0] (added until every GSR interval was within ±1 points: not " in md


def test_the_summary_counts_the_planner_errors_of_every_step(tmp_path: Path) -> None:
    run_dir = tmp_path / "run"
    backend = FakeBackend(success={"hsq": 0.7}, broken=("antipodal",))
    steps = []

    def run_seeds(cfg, base_seeds, resume):
        steps.append(base_seeds)
        return run_benchmark(cfg, run_dir, backend=backend, resume=resume, progress=False,
                             base_seeds=base_seeds)  # fmt: skip

    summary = run_until_halfwidth(CONFIG, run_dir, 0.1, 3, run_seeds)
    attempts = load_run(run_dir).attempts
    broken = attempts[attempts["outcome"] == "planner_error"]
    assert len(steps) > 1 and set(broken["planner"]) == {"antipodal"}
    assert summary.planner_errors == len(broken) == (attempts["planner"] == "antipodal").sum()
    assert summary.first_planner_error == "fake: planner 'antipodal' raised"
