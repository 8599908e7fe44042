"""The report's paired section: pairs, counts and verdicts from a run's files."""

from __future__ import annotations

import csv
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from hsqbench.experiment.config import ExperimentConfig, IsolatedConfig, PackedConfig
from hsqbench.experiment.holm import holm
from hsqbench.experiment.paired import mcnemar_exact
from hsqbench.experiment.paired_table import PAIRED_CSV, PAIRED_OBJECTS_CSV
from hsqbench.experiment.report import TABLES_MD, load_run, write_report
from hsqbench.experiment.runner import run_benchmark
from hsqbench.experiment.sign_flip import sign_flip_p
from hsqbench.experiment.verdicts import verdict_sections
from tests.fake_backend import FakeBackend

OBJECTS = ("mug", "bowl", "apple", "pear", "banana", "drill", "can", "box")
CONFIG = ExperimentConfig(
    planners=("hsq", "antipodal", "single-sq"),
    isolated=IsolatedConfig(objects=OBJECTS, attempts_per_object=6),
    packed=PackedConfig(objects=OBJECTS, rounds=8, objects_per_round=3),
)


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("paired") / "run"
    backend = FakeBackend(success={"hsq": 0.9, "antipodal": 0.3, "single-sq": 0.88})
    run_benchmark(CONFIG, path, backend=backend, progress=False)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no error trials: nothing to warn about
        write_report(path)
    return path


def _isolated_outcomes(run_dir: Path, planner: str) -> dict[str, bool]:
    """Presentation (trial key less the planner) -> success, straight from attempts.csv."""
    with open(run_dir / "attempts.csv") as f:
        return {
            r["trial_key"].replace(f"/{planner}/", "/"): r["success"] == "1"
            for r in csv.DictReader(f)
            if r["experiment"] == "isolated" and r["planner"] == planner
        }


def test_isolated_pairs_are_counted_presentation_by_presentation(run_dir: Path) -> None:
    paired = pd.read_csv(run_dir / PAIRED_CSV)
    row = paired[(paired["planner"] == "antipodal") & (paired["comparison"] == "isolated GSR")]
    row = row.iloc[0]
    mine, ref = _isolated_outcomes(run_dir, "antipodal"), _isolated_outcomes(run_dir, "hsq")
    won = sum(mine[k] and not ref[k] for k in mine)
    lost = sum(ref[k] and not mine[k] for k in mine)
    assert (row["only_planner"], row["only_reference"], row["pairs"]) == (won, lost, len(mine))
    assert row["presentations_p_value"] == pytest.approx(mcnemar_exact(won, lost))
    assert row["difference_pp"] == pytest.approx(100 * (won - lost) / len(mine))
    # The primary test is over objects: the sign-flip test of the per-object won - lost.
    per_object = {}
    for k in mine:
        obj = k.split("/")[2]
        per_object[obj] = per_object.get(obj, 0) + int(mine[k]) - int(ref[k])
    assert row["unit"] == "objects" and row["clusters"] == len(OBJECTS)
    assert row["p_value"] == pytest.approx(sign_flip_p(np.array(list(per_object.values()))))
    family = paired[paired["comparison"] == "isolated GSR"]
    assert family["p_holm"].to_numpy() == pytest.approx(holm(family["p_value"].to_numpy()))
    assert row["verdict"] == "worse" and row["p_holm"] < 0.05 and row["ci_high_pp"] < 0
    assert row["ci_low_pp"] <= row["difference_pp"]


def test_cr_pairs_are_the_objects_of_rounds_on_the_same_draw(run_dir: Path) -> None:
    with open(run_dir / "rounds.csv") as f:
        rounds = {(r["planner"], r["base_seed"], r["trial_index"]): r for r in csv.DictReader(f)}
    won = lost = pairs = 0
    for (planner, seed, index), r in rounds.items():
        if planner != "antipodal":
            continue
        ref = rounds[("hsq", seed, index)]
        assert r["objects"] == ref["objects"]
        for obj in r["objects"].split(";"):
            a, b = obj in r["objects_cleared"].split(";"), obj in ref["objects_cleared"].split(";")
            won, lost, pairs = won + (a and not b), lost + (b and not a), pairs + 1
    paired = pd.read_csv(run_dir / PAIRED_CSV)
    row = paired[(paired["planner"] == "antipodal") & (paired["comparison"] == "packed CR")]
    assert tuple(row.iloc[0][["only_planner", "only_reference", "pairs"]]) == (won, lost, pairs)
    # Rounds are the units; there is no test over objects of rounds.
    assert row.iloc[0]["unit"] == "rounds" and row.iloc[0]["clusters"] == 8
    assert np.isnan(row.iloc[0]["presentations_p_value"])


def test_clutter_gsr_pairs_the_rounds_with_each_planners_own_attempts(run_dir: Path) -> None:
    with open(run_dir / "attempts.csv") as f:
        rows = [r for r in csv.DictReader(f) if r["experiment"] == "packed"]
    count = {p: (sum(r["success"] == "1" for r in rows if r["planner"] == p),
                 sum(r["planner"] == p for r in rows)) for p in ("hsq", "antipodal")}  # fmt: skip
    paired = pd.read_csv(run_dir / PAIRED_CSV)
    row = paired[(paired["planner"] == "antipodal") & (paired["comparison"] == "packed GSR")]
    r = row.iloc[0]
    assert (r["planner_successes"], r["planner_attempts"]) == count["antipodal"]
    assert (r["reference_successes"], r["reference_attempts"]) == count["hsq"]
    gsr = {p: k / n for p, (k, n) in count.items()}
    assert r["difference_pp"] == pytest.approx(100 * (gsr["antipodal"] - gsr["hsq"]))
    assert r["unit"] == "rounds" and 0 < r["p_value"] <= 1 and np.isnan(r["pairs"])


def test_tables_md_says_the_verdicts_in_words(run_dir: Path) -> None:
    md = (run_dir / TABLES_MD).read_text()
    assert "## Paired comparison with hsq (same presentations)" in md
    line = next(x for x in md.splitlines() if x.startswith("| isolated GSR | antipodal vs hsq |"))
    assert "**worse**" in line
    line = next(x for x in md.splitlines() if x.startswith("| isolated GSR | single-sq vs hsq |"))
    assert "**not distinguishable**" in line  # 0.88 against 0.9 on 48 presentations of 8 objects
    assert "Holm's method within each comparison" in md
    per_object = pd.read_csv(run_dir / PAIRED_OBJECTS_CSV)
    assert set(per_object["object"]) == set(OBJECTS)
    assert (per_object.groupby("planner")["pairs"].sum() == 6 * len(OBJECTS)).all()


def test_another_reference_turns_the_comparison_round(run_dir: Path) -> None:
    data = load_run(run_dir)
    tables, lines = verdict_sections(data, "antipodal")
    paired = tables[PAIRED_CSV]
    row = paired[(paired["planner"] == "hsq") & (paired["comparison"] == "isolated GSR")]
    assert row.iloc[0]["verdict"] == "better"
    assert "## Paired comparison with antipodal (same presentations)" in lines
    with pytest.raises(ValueError, match="--reference contact-graspnet: no rows"):
        verdict_sections(data, "contact-graspnet")


def test_a_run_without_the_reference_says_so(run_dir: Path, tmp_path: Path) -> None:
    data = load_run(run_dir)
    data.attempts = data.attempts[data.attempts["planner"] != "hsq"]
    data.rounds = data.rounds[data.rounds["planner"] != "hsq"]
    data.planners = [p for p in data.planners if p != "hsq"]
    tables, lines = verdict_sections(data)
    assert PAIRED_CSV not in tables
    assert any("reference planner hsq did not run here" in x for x in lines)


def test_report_command_takes_the_reference(run_dir: Path, capsys) -> None:
    from hsqbench.cli import main

    assert main(["report", "--run", str(run_dir), "--reference", "single-sq"]) == 0
    md = (run_dir / TABLES_MD).read_text()
    assert "| isolated GSR | hsq vs single-sq |" in md
    assert main(["report", "--run", str(run_dir), "--reference", "gpd"]) == 2
    assert "--reference gpd: no rows of that planner" in capsys.readouterr().err
