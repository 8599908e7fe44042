"""Table IV (hsqbench.experiment.pile_table): pile GSR and CR from a run's files, GIGA as context."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from hsqbench.experiment.cluster import rate_over_clusters
from hsqbench.experiment.config import ExperimentConfig, IsolatedConfig, PackedConfig, PileConfig
from hsqbench.experiment.pile_table import CONTEXT, TABLE4_CSV
from hsqbench.experiment.report import TABLES_MD, write_report
from hsqbench.experiment.runner import run_benchmark
from tests.fake_backend import FakeBackend

OBJECTS = ("mug", "bowl", "pear", "banana", "apple")
CONFIG = ExperimentConfig(
    planners=("hsq", "antipodal", "oracle"),
    isolated=IsolatedConfig(enabled=False),
    packed=PackedConfig(objects=OBJECTS, rounds=2, objects_per_round=3),
    pile=PileConfig(enabled=True, objects=OBJECTS, rounds=6, objects_per_round=3),
)


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("pile") / "run"
    backend = FakeBackend(
        success={"antipodal": 0.3, "oracle": 0.95}, unplaceable=(("mug", "pear"),)
    )
    run_benchmark(CONFIG, path, backend=backend, progress=False)
    write_report(path)
    return path


def _rows(path: Path) -> list[dict[str, str]]:
    with open(path) as f:
        return list(csv.DictReader(f))


def _per_round(run_dir: Path, planner: str) -> dict[str, list[int]]:
    """Pile round trial key -> [successes, attempts, cleared, presented]."""
    out: dict[str, list[int]] = {}
    with open(run_dir / "rounds.csv") as f:
        for row in csv.DictReader(f):
            if row["trial_key"].startswith(f"pile/{planner}/"):
                out[row["trial_key"]] = [0, 0, int(row["n_cleared"]), int(row["n_objects"])]
    with open(run_dir / "attempts.csv") as f:
        for row in csv.DictReader(f):
            if row["experiment"] == "pile" and row["planner"] == planner and row["status"] == "ok":
                out[row["trial_key"]][1] += 1
                out[row["trial_key"]][0] += row["success"] == "1"
    return out


def _from_csv(run_dir: Path, planner: str) -> tuple[int, int, int, int]:
    k, n, cleared, presented = np.array(list(_per_round(run_dir, planner).values())).sum(axis=0)
    return int(k), int(n), int(cleared), int(presented)


def test_table4_counts_the_pile_rounds_only_with_intervals_over_rounds(run_dir: Path) -> None:
    t4 = pd.read_csv(run_dir / TABLE4_CSV)
    measured = t4[t4["source"] != CONTEXT].set_index("method")
    assert list(measured.index) == ["hsq", "antipodal", "oracle (privileged)"]
    for planner, label in (
        ("hsq", "hsq"),
        ("antipodal", "antipodal"),
        ("oracle", "oracle (privileged)"),
    ):
        k, n, cleared, presented = _from_csv(run_dir, planner)
        row = measured.loc[label]
        assert (row["successes"], row["attempts"]) == (k, n)
        assert (
            (row["objects_cleared"], row["objects_presented"])
            == (cleared, presented)
            == (
                cleared,
                6 * 3,
            )
        )
        assert row["rounds"] == 6
        per = np.array(list(_per_round(run_dir, planner).values()))
        low, high = rate_over_clusters(per[:, 0], per[:, 1], 0.95)
        assert row["gsr_percent"] == pytest.approx(100 * k / n)
        assert (row["gsr_ci_low_percent"], row["gsr_ci_high_percent"]) == pytest.approx(
            (100 * low, 100 * high), nan_ok=True
        )
        low, high = rate_over_clusters(per[:, 2], per[:, 3], 0.95)
        assert (row["cr_ci_low_percent"], row["cr_ci_high_percent"]) == pytest.approx(
            (100 * low, 100 * high), nan_ok=True
        )
        assert row["cr_percent"] == pytest.approx(100 * cleared / presented)
    # The packed rounds of the same run stay out of Table IV.
    packed_n = sum(
        1
        for r in _rows(run_dir / "attempts.csv")
        if r["experiment"] == "packed" and r["planner"] == "hsq"
    )
    assert packed_n > 0 and measured.loc["hsq", "attempts"] == _from_csv(run_dir, "hsq")[1]


def test_gigas_reported_pile_numbers_are_a_separate_context_row(run_dir: Path) -> None:
    t4 = pd.read_csv(run_dir / TABLE4_CSV)
    giga = t4[t4["source"] == CONTEXT]
    assert list(giga["method"]) == ["GIGA (pile)"]
    assert (giga["gsr_percent"].iloc[0], giga["cr_percent"].iloc[0]) == (69.3, 49.8)
    md = (run_dir / TABLES_MD).read_text()
    section = md[md.index("## Table IV") : md.index("## Outcomes")]
    lines = section.splitlines()
    sep = next(i for i, line in enumerate(lines) if "other harness, for context" in line)
    giga_line = next(i for i, line in enumerate(lines) if line.startswith("| GIGA (pile)"))
    hsq_line = next(i for i, line in enumerate(lines) if line.startswith("| hsq |"))
    assert hsq_line < sep < giga_line
    assert "| oracle (privileged) |" in section


def test_unpilable_draws_are_recorded_in_run_json_and_rounds_csv(run_dir: Path) -> None:
    meta = json.loads((run_dir / "run.json").read_text())
    piles = meta["pile_draws"]
    assert len(piles) == 6
    for entry in piles.values():
        assert not {"mug", "pear"} <= set(entry["objects"])
    redrawn = [k for k, v in piles.items() if v["rejected"]]
    notes = [
        r["detail"] for r in _rows(run_dir / "rounds.csv") if r["trial_key"].startswith("pile/hsq/")
    ]
    assert sum("did not settle into a pile" in n for n in notes) == len(redrawn)
    assert "pile" in {r["experiment"] for r in _rows(run_dir / "attempts.csv")}


def test_a_run_without_piles_has_no_table4(tmp_path: Path) -> None:
    config = ExperimentConfig(
        planners=("hsq",),
        isolated=IsolatedConfig(objects=("mug",), attempts_per_object=1),
        packed=PackedConfig(objects=OBJECTS, rounds=1, objects_per_round=2),
    )
    run_benchmark(config, tmp_path / "run", backend=FakeBackend(), progress=False)
    write_report(tmp_path / "run")
    assert not (tmp_path / "run" / TABLE4_CSV).exists()
    assert "Table IV" not in (tmp_path / "run" / TABLES_MD).read_text()


def test_table2_counts_the_packed_rounds_only(run_dir: Path) -> None:
    # Pile rounds share rounds.csv with packed ones: Table II's CR and round count must not
    # take them in (the run has 2 packed and 4 pile rounds of 3 objects per planner).
    t2 = pd.read_csv(run_dir / "table2_packed.csv").set_index("method")
    for planner in ("hsq", "antipodal"):
        rounds = [
            r
            for r in _rows(run_dir / "rounds.csv")
            if r["trial_key"].startswith(f"packed/{planner}/") and r["status"] == "ok"
        ]
        cleared = sum(int(r["n_cleared"]) for r in rounds)
        assert t2.loc[planner, "rounds"] == len(rounds) == 2
        assert t2.loc[planner, "objects_presented"] == 2 * 3
        assert t2.loc[planner, "objects_cleared"] == cleared
