"""``hsqbench assets build``: which objects it builds, and what it says when it cannot."""

from __future__ import annotations

import pytest

from hsqbench.assets.config import load_assets_config
from hsqbench.cli import main
from hsqbench.experiment.config import load_experiment_config


@pytest.fixture(autouse=True)
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("HSQ_CACHE_DIR", str(tmp_path / "cache"))
    return tmp_path / "cache"


def _selection(monkeypatch, *argv: str) -> list[str]:
    """The names `assets build ARGV` would build (the build itself is replaced)."""
    import hsqbench.commands.assets as command

    seen: list[list[str]] = []
    monkeypatch.setattr(command, "_build", lambda config, names, jobs: seen.append(names) or 0)
    assert main(["assets", "build", *argv]) == 0
    return seen[0]


def test_without_names_it_says_how_to_choose(capsys, monkeypatch):
    monkeypatch.delenv("HSQ_YCB_DIR", raising=False)
    assert main(["assets", "build"]) == 2
    err = capsys.readouterr().err
    assert "say which objects to build" in err
    n = len(load_assets_config().download.objects) + 5
    for way in ("--protocol paper", "--source procedural", f"all {n} objects", "--all"):
        assert way in err
    assert main(["assets", "build", "proc_box", "--all"]) == 2
    assert "not several" in capsys.readouterr().err


def test_names_protocol_source_and_all(monkeypatch):
    monkeypatch.delenv("HSQ_YCB_DIR", raising=False)
    assert _selection(monkeypatch, "proc_l", "proc_box") == ["proc_l", "proc_box"]
    procedural = ["proc_box", "proc_cylinder", "proc_sphere", "proc_l", "proc_mug"]
    assert _selection(monkeypatch, "--source", "procedural") == procedural
    # Without HSQ_YCB_DIR the YCB library is what can be downloaded (fetched before building).
    table = [o.name for o in load_assets_config().download.objects]
    assert _selection(monkeypatch, "--all") == table + procedural
    assert _selection(monkeypatch, "--source", "ycb") == table
    quick = load_experiment_config("quick")
    expected = list(dict.fromkeys(quick.isolated.objects + quick.packed.objects))
    assert _selection(monkeypatch, "--protocol", "quick") == expected


def test_a_failed_object_is_named_and_the_exit_code_says_so(tmp_path, cache, capsys):
    import trimesh

    folder = tmp_path / "meshes"
    folder.mkdir()
    (folder / "flat.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n")
    trimesh.creation.box(extents=(0.04, 0.05, 0.06)).export(folder / "block.stl")
    assert main(["assets", "import", str(folder), "--no-build"]) == 0
    fast = tmp_path / "fast.yaml"  # low CoACD effort (a config file replaces the whole config)
    fast.write_text("coacd: {preprocess_resolution: 20, mcts_iterations: 20, mcts_nodes: 10}\n")
    rc = main(["assets", "--assets-config", str(fast), "build", "flat", "block", "--jobs", "1"])
    captured = capsys.readouterr()
    assert rc == 1, captured.err
    assert "block" in captured.out and "1 objects ready" in captured.out
    assert "1 object(s) cannot be built:\n  flat: AssetError" in captured.err
    assert "flat.obj: the mesh is flat" in captured.err
