"""Object-level uncertainty of isolated GSR: the bootstrap over objects beside Wilson."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

from hsqbench.experiment.config import ExperimentConfig, IsolatedConfig, PackedConfig
from hsqbench.experiment.object_table import object_level, render_object_level
from hsqbench.experiment.report import load_run
from hsqbench.experiment.runner import run_benchmark
from hsqbench.experiment.stats import wilson_interval
from tests.fake_backend import FakeBackend

OBJECTS = ("mug", "bowl", "apple", "pear", "banana", "drill")


def _run(path: Path, objects: tuple[str, ...]) -> Path:
    config = ExperimentConfig(
        planners=("hsq", "antipodal"),
        isolated=IsolatedConfig(objects=objects, attempts_per_object=6),
        packed=PackedConfig(enabled=False),
    )
    run_benchmark(config, path, backend=FakeBackend(success={"antipodal": 0.4}), progress=False)
    return path


def test_each_planner_gets_both_intervals_and_its_worst_objects(tmp_path: Path) -> None:
    data = load_run(_run(tmp_path / "run", OBJECTS))
    table = object_level(data)
    assert list(table["planner"]) == ["hsq", "antipodal"]
    ok = data.attempts
    for _, r in table.iterrows():
        mine = ok[ok["planner"] == r["planner"]]
        k, n = int(mine["success"].sum()), len(mine)
        low, high = wilson_interval(k, n)
        assert (r["successes"], r["attempts"], r["objects"]) == (k, n, len(OBJECTS))
        assert r["wilson_low_percent"] == pytest.approx(100 * low)
        assert r["wilson_high_percent"] == pytest.approx(100 * high)
        assert r["objects_low_percent"] <= r["gsr_percent"] <= r["objects_high_percent"]
        per = mine.groupby("objects")["success"].mean()
        assert r["objects_under_50"] == int((per < 0.5).sum())
        worst = r["worst"].split(", ")[0].split(" ")[0]
        assert per[worst] == per.min()
    lines = render_object_level(data, table)
    assert lines[0] == "## Isolated GSR over objects (object-level uncertainty)"
    assert any(x.startswith("| antipodal (6 objects) |") for x in lines)


def test_too_few_objects_give_no_section(tmp_path: Path) -> None:
    data = load_run(_run(tmp_path / "few", OBJECTS[:3]))
    assert object_level(data).empty
    assert render_object_level(data, pd.DataFrame()) == []
