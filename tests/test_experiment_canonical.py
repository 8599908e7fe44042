"""`make results`: the canonical list is valid, and its logic makes and resumes every run (on the
quick protocol with the fake backend, so in seconds)."""

from __future__ import annotations

import pytest

from hsqbench.config import ConfigError, from_dict
from hsqbench.experiment.canonical import Canonical, load_canonical, main, make_results
from hsqbench.experiment.config import load_experiment_config
from hsqbench.experiment.results import ResultStore
from hsqbench.settings import SWEEP_DIR
from tests.fake_backend import FakeBackend


def test_every_canonical_run_names_a_protocol_with_its_experiments():
    canon = load_canonical()
    assert canon.runs and canon.sweeps is not None
    for run in canon.runs:
        config = load_experiment_config(run.config)
        assert set(run.experiments) <= set(config.enabled_experiments()), run.name
    for name in canon.sweeps.parameters:
        assert (SWEEP_DIR / f"{name}.yaml").is_file(), name
    assert 60 * 6 < canon.expected_min() < 60 * 16  # the documented "about 8.5 h"


def test_repeated_folder_names_and_paths_are_refused():
    run = {"name": "a", "config": "quick", "experiments": ["isolated"], "expected_min": 1}
    with pytest.raises(ConfigError, match="repeat"):
        from_dict(Canonical, {"runs": [run, run]})
    with pytest.raises(ConfigError, match="folder name"):
        from_dict(Canonical, {"runs": [{**run, "name": "x/y"}]})


def test_make_results_on_the_quick_protocol_makes_then_resumes_each_run(tmp_path, capsys):
    canon = load_canonical()
    benchmark_runs = {r.name for r in canon.runs}

    def fake(config):
        return FakeBackend(default_success=0.7)

    errors = make_results(
        canon, tmp_path, only=benchmark_runs, protocol="quick", backend_factory=fake, progress=False
    )
    assert errors == 0
    quick = load_experiment_config("quick")
    made = {p.name for p in tmp_path.iterdir()}
    # The pile run is skipped: the quick protocol has no pile experiment.
    expected = {r.name for r in canon.runs if set(r.experiments) & set(quick.enabled_experiments())}
    assert made == expected
    for name in made:
        assert ResultStore(tmp_path / name).attempts_path.is_file()
        assert "measured, fake backend" in (tmp_path / name / "tables.md").read_text()
    out = capsys.readouterr().out
    assert "quick has none of pile" in out

    rows = {n: (tmp_path / n / "attempts.csv").read_text() for n in made}
    assert (
        make_results(
            canon,
            tmp_path,
            only=benchmark_runs,
            protocol="quick",
            backend_factory=fake,
            progress=False,
        )
        == 0
    )
    assert {n: (tmp_path / n / "attempts.csv").read_text() for n in made} == rows  # nothing rerun


def test_dry_run_states_the_expected_time_and_unknown_names_fail(capsys):
    assert main(["--dry-run"]) == 0
    assert "expected: about" in capsys.readouterr().out
    with pytest.raises(SystemExit):
        main(["--dry-run", "--only", "nosuchrun"])
    assert "not in the list" in capsys.readouterr().err
