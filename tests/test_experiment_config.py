"""Protocol configs: object lists, ``all`` with ``exclude``, and the objects a run needs."""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest

from hsqbench.errors import ConfigError
from hsqbench.experiment.config import (
    YCB_OBJECTS,
    ExperimentConfig,
    IsolatedConfig,
    PackedConfig,
    load_experiment_config,
)
from hsqbench.settings import PROTOCOL_DIR, REPO_ROOT

YCB = os.environ.get("HSQ_YCB_DIR")
needs_ycb = pytest.mark.skipif(not YCB or not Path(YCB).is_dir(), reason="HSQ_YCB_DIR is not set")


def test_object_names_are_the_union_of_enabled_experiments_in_first_use_order():
    cfg = ExperimentConfig(
        isolated=IsolatedConfig(objects=("a", "b")),
        packed=PackedConfig(objects=("b", "c", "d"), objects_per_round=2),
    )
    assert cfg.object_names() == ("a", "b", "c", "d")
    off = ExperimentConfig(
        isolated=IsolatedConfig(objects=("a",), enabled=False),
        packed=PackedConfig(objects=("c", "d"), objects_per_round=2),
    )
    assert off.object_names() == ("c", "d")


def test_exclude_takes_names_out_and_rejects_unknown_ones():
    assert IsolatedConfig(objects=("a", "b", "c"), exclude=("b",)).objects == ("a", "c")
    with pytest.raises(ConfigError, match=r"exclude names \['z'\]"):
        IsolatedConfig(objects=("a", "b"), exclude=("z",))
    with pytest.raises(ConfigError, match="a list of names or 'all'"):
        IsolatedConfig(objects="everything")


@needs_ycb
def test_all_is_every_ycb_object_of_the_folder_less_the_excluded():
    from hsqbench.assets.library import ycb_names

    cfg = IsolatedConfig(objects="all", exclude=YCB_OBJECTS)
    assert cfg.objects == tuple(n for n in ycb_names() if n not in YCB_OBJECTS)
    assert len(cfg.objects) == len(ycb_names()) - len(YCB_OBJECTS)


@needs_ycb
def test_the_unseen_object_protocol_holds_no_paper_object():
    cfg = load_experiment_config("ycb")
    for exp in cfg.enabled_experiments():
        assert not set(getattr(cfg, exp).objects) & set(YCB_OBJECTS)
    assert "oracle" in cfg.planners


def test_a_protocol_runs_only_the_experiments_it_names(tmp_path, capsys):
    from hsqbench.experiment.config import load_experiment_config

    path = tmp_path / "mine.yaml"
    path.write_text("planners: [hsq]\nseeds: [0]\nisolated: {objects: [proc_box]}\n")
    config = load_experiment_config(path)
    assert config.enabled_experiments() == ("isolated",)  # not the paper's 15 packed rounds
    assert config.object_names() == ("proc_box",)
    assert capsys.readouterr().err == ""  # every default that matters was stated


def test_a_protocol_says_which_defaults_it_took(tmp_path, capsys):
    from hsqbench.experiment.config import load_experiment_config

    path = tmp_path / "mine.yaml"
    path.write_text("packed: {objects: [proc_box, proc_cylinder], objects_per_round: 2}\n")
    config = load_experiment_config(path)
    assert config.enabled_experiments() == ("packed",)
    assert capsys.readouterr().err == (
        "mine.yaml: not stated, default taken: planners ['hsq', 'single-sq', 'antipodal']; "
        "seeds [0]\n"
    )


def test_a_protocol_naming_no_experiment_is_refused(tmp_path):
    from hsqbench.experiment.config import load_experiment_config

    path = tmp_path / "mine.yaml"
    path.write_text("planners: [hsq]\nseeds: [0]\n")
    with pytest.raises(ConfigError) as err:
        load_experiment_config(path)
    assert str(err.value) == (
        "mine.yaml names no experiment: add a section for one of ['isolated', 'packed', "
        "'pile'], e.g. isolated: {objects: [mug], attempts_per_object: 1}"
    )


PROTOCOLS = sorted(p.stem for p in PROTOCOL_DIR.glob("*.yaml"))


@pytest.mark.parametrize("name", PROTOCOLS)
def test_every_protocol_loads_by_its_bare_name(name):
    cfg = load_experiment_config(name)
    assert cfg.planners and cfg.enabled_experiments()


def test_the_documented_protocols_are_the_shipped_ones():
    """docs/protocols.md has a section per protocol and per built-in sweep, and no other."""
    text = (REPO_ROOT / "docs" / "protocols.md").read_text()
    documented = set(re.findall(r"^### `([a-z0-9_]+)`", text, flags=re.M))
    sweeps = {p.stem for p in (PROTOCOL_DIR / "sweeps").glob("*.yaml")}
    assert documented == set(PROTOCOLS) | sweeps


def test_a_variant_that_extends_a_protocol_by_name_works_from_any_folder(tmp_path, monkeypatch):
    """What docs/protocols.md tells a user to write: a file of their own, anywhere, naming the
    protocol it changes and stating only the change."""
    variant = tmp_path / "variants" / "paper3_hsq.yaml"
    variant.parent.mkdir()
    variant.write_text("extends: paper3\nplanners: [hsq, hsq-paper]\npacked:\n  enabled: false\n")
    monkeypatch.chdir(tmp_path)
    cfg = load_experiment_config("variants/paper3_hsq.yaml")
    base = load_experiment_config("paper3")
    assert cfg.planners == ("hsq", "hsq-paper") and cfg.seeds == base.seeds == (0, 1, 2)
    assert cfg.enabled_experiments() == ("isolated",)
    assert cfg.isolated == base.isolated  # everything it does not name is the protocol's
