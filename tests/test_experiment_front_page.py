"""README.md's headline tables come from the runs under results/, and say which code made them."""

from __future__ import annotations

import json
import shutil

import pandas as pd
import pytest

from hsqbench.experiment.canonical import load_canonical, make_results
from hsqbench.experiment.front_page import TABLES, FrontPageError, main, update
from hsqbench.experiment.markdown import p_text
from hsqbench.settings import REPO_ROOT
from tests.fake_backend import FakeBackend


def test_the_readme_tables_are_those_of_the_committed_results():
    text = (REPO_ROOT / "README.md").read_text()
    for name, (folder, _) in TABLES.items():
        if (REPO_ROOT / "results" / folder).is_dir():  # a canonical run the README must show
            assert f"<!-- table: {name} -->" in text, name
    assert update(text, REPO_ROOT / "results") == text, (
        "README.md's tables differ from results/: run `python -m hsqbench.experiment.front_page`"
    )


@pytest.fixture(scope="module")
def quick_results(tmp_path_factory):
    """The canonical runs made on the quick protocol (two planners) with the fake backend."""
    out = tmp_path_factory.mktemp("results")
    protocol = out.parent / "quick2.yaml"
    protocol.write_text("extends: quick\nplanners: [hsq, antipodal]\n")
    canon = load_canonical()
    made = make_results(
        canon,
        out,
        only={"paper3", "ycb3"},
        protocol=str(protocol),
        backend_factory=lambda config: FakeBackend(default_success=0.7),
        progress=False,
    )
    assert made == 0
    return out


def _readme(*names: str) -> str:
    return "# t\n" + "".join(f"<!-- table: {n} -->\nstale\n<!-- /table -->\n" for n in names)


def test_blocks_are_rewritten_from_the_runs_with_their_code_version(quick_results):
    text = update(_readme("paper-isolated", "unseen-packed"), quick_results)
    assert "stale" not in text
    meta = json.loads((quick_results / "paper3" / "run.json").read_text())
    assert f"code `{meta['code_version']}`: `results/paper3/`" in text
    measured = pd.read_csv(quick_results / "paper3" / "table1_isolated.csv")
    measured = measured[measured["source"].str.startswith("measured")]
    assert len(measured) == 2
    for row in measured.itertuples():
        line = next(ln for ln in text.splitlines() if ln.startswith(f"| {row.method} |"))
        assert f"{int(row.successes)}/{int(row.attempts)}" in line
        # every planner but the reference carries its paired difference to hsq
        assert ("reference" in line) == (row.method == "hsq") and (", p " in line) != (
            row.method == "hsq"
        )
    # the paired cell carries the Holm-adjusted p of the test over objects, and a line says so
    paired = pd.read_csv(quick_results / "paper3" / "paired.csv").set_index("comparison")
    row = paired.loc["isolated GSR"]
    line = next(ln for ln in text.splitlines() if ln.startswith("| antipodal |"))
    assert line.rstrip(" |").endswith(f"p {p_text(row['p_holm'])}")
    assert "vs hsq over objects, paired" in text
    assert "p Holm-adjusted over the 1 planners of this table" in text
    # the paper's reported rows beside its own objects, never beside the unseen ones
    head, unseen = text.split("<!-- table: unseen-packed -->")
    assert "reported, real robot" in head and "reported" not in unseen
    assert update(text, quick_results) == text  # idempotent: --check passes after a write


def test_unseen_objects_show_the_interval_over_objects_first(quick_results, tmp_path):
    results = tmp_path / "results"
    shutil.copytree(quick_results, results)
    text = update(_readme("unseen-isolated"), results)  # two objects: no interval over them
    line = next(ln for ln in text.splitlines() if ln.startswith("| hsq |"))
    assert line.split(" | ")[2] == ""
    pd.DataFrame(
        {
            "planner": ["hsq", "antipodal"],
            "objects_low_percent": [61.04, 40.0],
            "objects_high_percent": [88.96, 70.0],
        }
    ).to_csv(results / "ycb3" / "object_level.csv", index=False)
    text = update(_readme("unseen-isolated"), results)
    head = next(ln for ln in text.splitlines() if ln.startswith("| planner |"))
    assert head.startswith("| planner | GSR | 95 % CI over objects | 95 % CI, Wilson |")
    line = next(ln for ln in text.splitlines() if ln.startswith("| hsq |"))
    assert line.split(" | ")[2] == "[61.0, 89.0]"


def test_a_missing_run_or_block_says_what_to_do(quick_results, tmp_path):
    with pytest.raises(FrontPageError, match="make results"):
        update(_readme("paper-pile"), quick_results)  # the quick protocol has no piles
    with pytest.raises(FrontPageError, match="not one of"):
        update(_readme("nosuch"), quick_results)
    with pytest.raises(FrontPageError, match="no <!-- table"):
        update("# nothing here\n", quick_results)


def test_check_fails_on_a_stale_readme_and_write_fixes_it(quick_results, tmp_path, capsys):
    readme = tmp_path / "README.md"
    readme.write_text(_readme("paper-packed"))
    args = ["--readme", str(readme), "--results", str(quick_results)]
    assert main([*args, "--check"]) == 1
    assert "differ" in capsys.readouterr().err
    assert main(args) == 0 and main([*args, "--check"]) == 0
    assert "CR vs hsq over rounds, paired" in readme.read_text()
