"""`make results`: the canonical list is valid, and its logic makes and resumes every run (on the
quick protocol with the fake backend, so in seconds)."""

from __future__ import annotations

import gzip

import pytest

from hsqbench.config import ConfigError, from_dict
from hsqbench.experiment.canonical import (
    Canonical,
    load_canonical,
    main,
    make_results,
    pack_attempts,
    unpack_attempts,
)
from hsqbench.experiment.config import load_experiment_config
from hsqbench.experiment.report import load_run
from hsqbench.experiment.results import ResultStore
from hsqbench.planner.registry import resolve_planners
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
    assert 60 * 6 < canon.expected_min() < 60 * 16  # the documented "about 7 hours"


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
        # A finished run is stored packed; its rows read back as the run made them.
        assert not ResultStore(tmp_path / name).attempts_path.exists()
        assert len(load_run(tmp_path / name).attempts) > 0
        assert "measured, fake backend" in (tmp_path / name / "tables.md").read_text()
    out = capsys.readouterr().out
    assert "quick has none of pile" in out
    # A run that names its planners (plugin specs) runs those, not its protocol's.
    named = [r for r in canon.runs if r.planners and r.name in made]
    assert named
    for run in named:
        ran = set(load_run(tmp_path / run.name).attempts["planner"])
        assert ran == set(resolve_planners(run.planners)) and not ran & set(quick.planners)

    rows = {n: (tmp_path / n / "attempts.csv.gz").read_bytes() for n in made}
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
    # Unpacked, resumed with nothing to rerun, packed again to the same bytes.
    assert {n: (tmp_path / n / "attempts.csv.gz").read_bytes() for n in made} == rows


def test_packing_is_reproducible_and_unpacking_restores_the_file(tmp_path):
    run = tmp_path / "r"
    run.mkdir()
    text = b"trial_key,outcome\na,success\nb,empty\n"
    (run / "attempts.csv").write_bytes(text)
    [packed] = pack_attempts(run)
    first = packed.read_bytes()
    assert packed.name == "attempts.csv.gz"
    assert not (run / "attempts.csv").exists() and gzip.decompress(first) == text
    unpack_attempts(run)
    assert (run / "attempts.csv").read_bytes() == text and not (run / "attempts.csv.gz").exists()
    assert pack_attempts(run)[0].read_bytes() == first  # no time or name in the header
    (run / "attempts.csv").write_bytes(text)
    with pytest.raises(FileExistsError, match=r"both attempts\.csv and attempts\.csv\.gz"):
        unpack_attempts(run)


def test_a_large_packed_file_is_stored_in_pieces_that_read_as_one(tmp_path, monkeypatch):
    from hsqbench.experiment import rows
    from hsqbench.experiment.results import ATTEMPT_COLUMNS, read_rows

    monkeypatch.setattr(rows, "PACKED_PIECE_BYTES", 200)
    run = tmp_path / "r"
    run.mkdir()
    keys = [f"isolated/hsq/s0/obj{i:04d}/{i * 7919 % 1000:03d}" for i in range(300)]
    lines = [",".join(ATTEMPT_COLUMNS)] + [k + "," * (len(ATTEMPT_COLUMNS) - 1) for k in keys]
    text = ("\n".join(lines) + "\n").encode()
    (run / "attempts.csv").write_bytes(text)
    pieces = pack_attempts(run)
    assert [p.name for p in pieces] == [f"attempts.csv.gz.{i:02d}" for i in range(len(pieces))]
    assert len(pieces) > 2 and all(p.stat().st_size <= 200 for p in pieces)
    assert rows.has_attempts(run) and not (run / "attempts.csv.gz").exists()
    parsed = read_rows(run / "attempts.csv", ATTEMPT_COLUMNS)  # readers join the pieces
    assert [r["trial_key"] for r in parsed.rows] == keys
    before = [p.read_bytes() for p in pieces]
    unpack_attempts(run)
    assert (run / "attempts.csv").read_bytes() == text
    assert not list(run.glob("attempts.csv.gz*"))
    assert [p.read_bytes() for p in pack_attempts(run)] == before
    # Under a larger limit the same rows pack into one file, and no old piece is left behind.
    monkeypatch.setattr(rows, "PACKED_PIECE_BYTES", 1 << 20)
    assert rows.write_packed(run / "attempts.csv.gz", text) == [run / "attempts.csv.gz"]
    assert sorted(p.name for p in run.iterdir()) == ["attempts.csv.gz"]


def test_dry_run_states_the_expected_time_and_unknown_names_fail(capsys):
    assert main(["--dry-run"]) == 0
    assert "expected: about" in capsys.readouterr().out
    with pytest.raises(SystemExit):
        main(["--dry-run", "--only", "nosuchrun"])
    assert "not in the list" in capsys.readouterr().err
