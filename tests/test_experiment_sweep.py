"""Sweeps (hsqbench.experiment.sweep*): each point an ordinary resumable run, the CSV's rates
and intervals, one plot per parameter, and the sweep config's checks. The fake backend stands in
for the simulation: its success probability is the point's setting."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from hsqbench.cli import CommandError, build_parser
from hsqbench.commands.sweep import _sweeps
from hsqbench.errors import ConfigError
from hsqbench.experiment.results import load_results
from hsqbench.experiment.stats import Rate
from hsqbench.experiment.sweep import CSV_FILE, SWEEP_FILE, point_config, run_sweep
from hsqbench.experiment.sweep_config import (
    SweepConfig,
    SweepParameter,
    SweepPoint,
    SweepProtocol,
    load_sweep_config,
)
from tests.fake_backend import FakeBackend

PROTOCOL = """
planners: [a, b]
seeds: [0]
isolated: {objects: [mug, bowl, apple], attempts_per_object: 10}
packed: {objects: [mug, bowl, apple], rounds: 3, objects_per_round: 2}
"""


def fake(trial_config: str, overrides: dict) -> FakeBackend:
    p = overrides.get("p", 0.8)
    return FakeBackend(success={"a": p, "b": p / 2})


@pytest.fixture
def sweep(tmp_path) -> SweepConfig:
    path = tmp_path / "proto.yaml"
    path.write_text(PROTOCOL)
    return SweepConfig(
        protocols=(SweepProtocol(str(path), attempts_per_object=4),),
        planners=("a", "b"),
        seeds=(0, 1),
        parameters=(
            SweepParameter(name="p", path="p", values=(0.2, 0.8)),
            SweepParameter(
                name="q",
                points=(SweepPoint("default", {}), SweepPoint("low", {"p": 0.1})),
            ),
        ),
    )


def test_points_are_runs_the_csv_holds_each_rate_and_a_plot_per_parameter(tmp_path, sweep):
    root = tmp_path / "sw"
    summary = run_sweep(sweep, root, backend_factory=fake, progress=False)
    # p=0.2, p=0.8, the default ({}), p=0.1: four distinct settings, four runs
    assert len(summary.runs) == 4
    assert all(s.ran == s.selected == 2 * 2 * 3 * 4 for s in summary.runs.values())
    table = pd.read_csv(root / CSV_FILE)
    assert set(table["parameter"]) == {"p", "q"}
    assert len(table) == 2 * 2 * 2  # parameters x points x planners (isolated only)
    meta = json.loads((root / SWEEP_FILE).read_text())
    for _, row in table.iterrows():
        run = root / row["run"]
        rows = [
            r
            for r in load_results(run).attempts
            if r["planner"] == row["planner"] and r["experiment"] == "isolated"
        ]
        k = sum(r["success"] == "1" for r in rows)
        assert (row["n"], row["successes"]) == (len(rows), k) == (24, k)
        rate = Rate.of(k, len(rows))
        assert row["gsr_percent"] == pytest.approx(100 * rate.value, rel=1e-3)
        assert row["gsr_ci_low_percent"] == pytest.approx(100 * rate.low, rel=1e-3)
        assert row["gsr_ci_high_percent"] == pytest.approx(100 * rate.high, rel=1e-3)
        point = meta["parameters"][row["parameter"]]["points"][row["point"]]
        assert json.loads(row["overrides"]) == point["overrides"]
        assert json.loads((run / "run.json").read_text())["backend"]["success"]["a"] == (
            point["overrides"].get("p", 0.8)
        )
    # the setting shows in the rates: planner a at p=0.8 beats p=0.2
    a = table[(table["parameter"] == "p") & (table["planner"] == "a")].set_index("value")
    assert a.loc["0.8", "gsr_percent"] > a.loc["0.2", "gsr_percent"]
    for name in ("p", "q"):
        assert (root / f"{name}.png").read_bytes()[:4] == b"\x89PNG"


def test_rerunning_resumes_every_point_and_new_seeds_get_new_runs(tmp_path, sweep):
    root = tmp_path / "sw"
    first = run_sweep(sweep, root, backend_factory=fake, progress=False)
    again = run_sweep(sweep, root, backend_factory=fake, progress=False)
    assert set(again.runs) == set(first.runs)
    assert all(s.ran == 0 and s.skipped == s.selected for s in again.runs.values())
    more = run_sweep(replace(sweep, seeds=(0, 1, 2)), root, backend_factory=fake, progress=False)
    assert not set(more.runs) & set(first.runs)  # other sizes never resume into old runs


def test_a_protocol_run_alone_keeps_the_other_protocols_runs(tmp_path, sweep):
    other = tmp_path / "other.yaml"
    other.write_text(PROTOCOL)
    both = replace(sweep, protocols=(*sweep.protocols, SweepProtocol(str(other), seeds=(0,))))
    root = tmp_path / "sw"
    first = run_sweep(both, root, backend_factory=fake, progress=False)
    before = pd.read_csv(root / CSV_FILE)
    # The second protocol again, alone, on three seeds: new runs for it, the first's are kept.
    alone = replace(both, protocols=(SweepProtocol(str(other), seeds=(0, 1, 2)),))
    again = run_sweep(alone, root, backend_factory=fake, progress=False)
    assert not set(again.runs) & set(first.runs)
    after = pd.read_csv(root / CSV_FILE)
    kept = after[after["protocol"] == "proto"].reset_index(drop=True)
    pd.testing.assert_frame_equal(
        kept, before[before["protocol"] == "proto"].reset_index(drop=True)
    )
    assert set(after[after["protocol"] == "other"]["n"]) == {3 * 3 * 10}  # seeds x objects x poses
    meta = json.loads((root / SWEEP_FILE).read_text())["parameters"]["p"]
    assert [(p["config"], p["seeds"]) for p in meta["protocols"]] == [
        (str(tmp_path / "proto.yaml"), [0, 1]),
        (str(other), [0, 1, 2]),
    ]
    # A parameter whose points changed starts its record afresh.
    moved = replace(alone, parameters=(SweepParameter(name="p", path="p", values=(0.3,)),))
    run_sweep(moved, root, backend_factory=fake, progress=False)
    meta = json.loads((root / SWEEP_FILE).read_text())["parameters"]["p"]
    assert [set(p["runs"]) for p in meta["points"]] == [{"other"}]


def test_planners_run_one_at_a_time_share_the_points_runs(tmp_path, sweep):
    root = tmp_path / "sw"
    first = run_sweep(sweep, root, backend_factory=fake, planners=("a",), progress=False)
    later = run_sweep(sweep, root, backend_factory=fake, planners=("b",), progress=False)
    assert set(later.runs) == set(first.runs)
    table = pd.read_csv(root / CSV_FILE)
    assert set(table["planner"]) == {"a", "b"} and set(table["n"]) == {2 * 3 * 4}


def test_cli_planners_pick_what_runs_without_changing_the_sweeps_runs():
    from hsqbench.cli import build_parser
    from hsqbench.commands.sweep import _sweeps, run_planners

    full = load_sweep_config("cameras").planners
    args = build_parser().parse_args(["sweep", "cameras", "--planners", "hsq", "antipodal"])
    (sweep,) = _sweeps(args)
    assert sweep.planners == full  # the points' run folders do not depend on --planners
    assert run_planners(args, sweep) == ("hsq", "antipodal")
    args = build_parser().parse_args(["sweep", "cameras", "--planners", "hsq-paper"])
    (sweep,) = _sweeps(args)
    assert sweep.planners == (*full, "hsq-paper") and run_planners(args, sweep) == ("hsq-paper",)


def test_packed_rows_carry_the_clearance_rate(tmp_path, sweep):
    packed = replace(sweep, experiments=("packed",), parameters=sweep.parameters[:1])
    run_sweep(packed, tmp_path / "sw", backend_factory=fake, progress=False)
    table = pd.read_csv(tmp_path / "sw" / CSV_FILE)
    assert set(table["experiment"]) == {"packed"}
    row = table.iloc[0]
    assert row["objects_presented"] == 2 * 3 * 2  # seeds x rounds x objects per round
    rate = Rate.of(int(row["objects_cleared"]), int(row["objects_presented"]))
    assert row["cr_percent"] == pytest.approx(100 * rate.value, rel=1e-3)


def test_packed_points_are_paired_with_the_default_on_the_clearance_rate(tmp_path, sweep):
    # CR is tested over rounds: four seeds of three rounds, enough for a verdict after Holm.
    packed = replace(
        sweep, seeds=(0, 1, 2, 3), experiments=("packed",), parameters=sweep.parameters[1:]
    )
    run_sweep(packed, tmp_path / "sw", backend_factory=fake, progress=False)
    q = pd.read_csv(tmp_path / "sw" / CSV_FILE).set_index(["value", "planner"])
    assert np.isnan(q.loc[("default", "a"), "vs_default_difference_pp"])
    for planner in ("a", "b"):  # every round pairs (same draws): the CR difference itself
        low, default = q.loc[("low", planner)], q.loc[("default", planner)]
        assert low["objects_presented"] == default["objects_presented"]
        assert low["vs_default_difference_pp"] == pytest.approx(
            low["cr_percent"] - default["cr_percent"], abs=0.01
        )
    assert q.loc[("low", "a"), "vs_default_verdict"] == "worse"
    assert q.loc[("low", "a"), "vs_default_p_value"] <= q.loc[("low", "a"), "vs_default_p_holm"]


def test_point_config_sizes_the_protocol_and_keeps_only_the_sweeps_experiments(sweep):
    config = point_config(sweep.protocols[0], sweep)
    assert config.isolated.attempts_per_object == 4 and config.isolated.enabled
    assert not config.packed.enabled and config.seeds == (0, 1)
    assert config.isolated.objects == ("mug", "bowl", "apple")
    # A protocol's own seeds win over the sweep's.
    own = point_config(replace(sweep.protocols[0], seeds=(5, 6, 7)), sweep)
    assert own.seeds == (5, 6, 7) and own.isolated.attempts_per_object == 4


def test_sweep_config_errors_name_the_problem():
    with pytest.raises(ConfigError, match="either path with values, or points"):
        SweepParameter(name="x", path="a.b", values=(1,), points=(SweepPoint("p", {}),))
    with pytest.raises(ConfigError, match="labels repeat"):
        SweepParameter(name="x", points=(SweepPoint("p", {}), SweepPoint("p", {"a": 1})))
    with pytest.raises(ConfigError, match="on every point or on none"):
        SweepParameter(name="x", points=(SweepPoint("p", {}, 1.0), SweepPoint("q", {"a": 1})))
    with pytest.raises(ConfigError, match=r"seeds \[1, 1\] must be distinct"):
        SweepProtocol("paper", seeds=(1, 1))
    with pytest.raises(ConfigError, match="letters, digits"):
        SweepParameter(name="a/b", path="a", values=(1,))
    values = SweepParameter(name="x", path="a.b", values=(0.5, 1))
    assert [(p.label, p.x, p.overrides) for p in values.points] == [
        ("0.5", 0.5, {"a.b": 0.5}),
        ("1", 1.0, {"a.b": 1}),
    ]
    cams = SweepParameter(name="c", path="c", values=(["l"], ["l", "r"]))
    assert cams.categorical and [p.label for p in cams.points] == ["l", "l+r"]


@pytest.mark.parametrize("name", ["depth_noise", "calibration", "cameras", "pad_friction"])
def test_built_in_sweeps_load_and_every_point_is_a_valid_trial_config(name):
    from hsqbench.sim.trial import load_trial_config

    sweep = load_sweep_config(name)
    assert [p.config for p in sweep.protocols] == ["paper", "ycb"]
    # Both protocols run three base seeds, as every GSR the README quotes: the paper's 15 by
    # their own seeds, the unseen objects by the sweep's.
    assert point_config(sweep.protocols[0], sweep).seeds == (0, 1, 2)
    unseen = sweep.protocols[1]
    assert unseen.seeds is None and point_config(unseen, sweep).seeds == (0, 1, 2)
    for proto in sweep.protocols:
        config = point_config(proto, sweep)
        for point in sweep.parameters[0].points:
            load_trial_config(config.trial_config, point.overrides or None)
    assert any(not p.overrides for p in sweep.parameters[0].points)  # today's setting is a point


def test_cli_builds_an_ad_hoc_sweep_with_yaml_values():
    from hsqbench.cli import CommandError, build_parser
    from hsqbench.commands.sweep import _sweeps

    args = build_parser().parse_args(
        ["sweep", "--param", "scene.depth_cameras.names", "--values", "[cam_left]", "[cam_right]"]
    )
    (sweep,) = _sweeps(args)
    assert [p.overrides for p in sweep.parameters[0].points] == [
        {"scene.depth_cameras.names": ["cam_left"]},
        {"scene.depth_cameras.names": ["cam_right"]},
    ]
    args = build_parser().parse_args(["sweep", "cameras", "--seeds", "3", "4"])
    (sweep,) = _sweeps(args)
    assert sweep.seeds == (3, 4) and sweep.parameters[0].name == "cameras"
    # --seeds replaces the protocols' own seeds too; --attempts-per-object keeps them.
    assert all(point_config(p, sweep).seeds == (3, 4) for p in sweep.protocols)
    (sweep,) = _sweeps(build_parser().parse_args(["sweep", "cameras", "--protocols", "ycb"]))
    assert [p.name for p in sweep.protocols] == ["ycb"]
    with pytest.raises(
        CommandError, match="not a protocol of sweep 'cameras'; its protocols: paper, ycb"
    ):
        _sweeps(build_parser().parse_args(["sweep", "cameras", "--protocols", "ycbb"]))
    args = build_parser().parse_args(["sweep", "cameras", "--attempts-per-object", "2"])
    (sweep,) = _sweeps(args)
    paper, ycb = sweep.protocols
    assert paper.attempts_per_object == ycb.attempts_per_object == 2
    assert paper.seeds == (0, 1, 2) and ycb.seeds is None
    with pytest.raises(CommandError, match="go together"):
        _sweeps(build_parser().parse_args(["sweep", "--param", "a.b"]))


def test_a_bad_override_fails_before_anything_is_written(tmp_path, sweep):
    bad = replace(
        sweep, parameters=(SweepParameter(name="x", path="perception.tof.sigma", values=(1.0,)),)
    )
    with pytest.raises(
        ConfigError, match=r"'sigma' is not a key of perception\.tof.*sigma_quad_per_m"
    ):
        run_sweep(bad, tmp_path / "sw", progress=False)  # the simulation backend checks it
    assert not (tmp_path / "sw").exists()
    with pytest.raises(ConfigError, match=r"no sweep 'nosuch'.*depth_noise"):
        load_sweep_config("nosuch")


def test_learned_views_points_are_valid_and_the_near_cameras_look_at_the_workspace():
    import mujoco

    from hsqbench.settings import REPO_ROOT
    from hsqbench.sim.trial import load_trial_config

    sweep = load_sweep_config("learned_views")
    (proto,) = sweep.protocols
    config = point_config(proto, sweep)
    model = mujoco.MjModel.from_xml_path(str(REPO_ROOT / "scenes" / "cameras.xml"))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    target = np.array([0.5, 0.0, 0.05])
    used = set()
    for point in sweep.parameters[0].points:
        trial = load_trial_config(config.trial_config, point.overrides or None)
        for name in trial.scene.depth_cameras.names:
            cam = model.camera(name).id
            forward = -data.cam_xmat[cam].reshape(3, 3)[:, 2]  # a MuJoCo camera looks along -z
            to_target = target - data.cam_xpos[cam]
            assert np.dot(forward, to_target) / np.linalg.norm(to_target) > 0.9999, name
            used.add(name)
    near = {"cam_near_left", "cam_near_right"}
    assert near <= used
    for name in near:  # 0.6 m away, 30 deg from vertical, as the networks' training views
        offset = data.cam_xpos[model.camera(name).id] - target
        assert np.linalg.norm(offset) == pytest.approx(0.6, abs=1e-3)
        assert np.degrees(np.arccos(offset[2] / np.linalg.norm(offset))) == pytest.approx(
            30, abs=0.1
        )


def test_isolated_points_are_paired_with_the_default_point(tmp_path, sweep):
    root = tmp_path / "sw"
    run_sweep(sweep, root, backend_factory=fake, progress=False)
    table = pd.read_csv(root / CSV_FILE)
    paired = [c for c in table.columns if c.startswith("vs_default_")]
    # Parameter p has no point without overrides: nothing to pair with.
    assert table.loc[table["parameter"] == "p", paired].isna().all().all()
    q = table[table["parameter"] == "q"].set_index(["value", "planner"])
    assert q.loc["default", paired].isna().all().all()  # the default against itself
    for planner in ("a", "b"):
        low = q.loc[("low", planner)]
        by_key = {}
        for label in ("low", "default"):
            rows = load_results(root / q.loc[(label, planner), "run"]).attempts
            by_key[label] = {
                r["trial_key"]: r["success"] == "1"
                for r in rows
                if r["planner"] == planner and r["experiment"] == "isolated"
            }
        keys = sorted(by_key["default"])
        assert sorted(by_key["low"]) == keys  # the same presentations at both points
        mine = np.array([by_key["low"][k] for k in keys])
        ref = np.array([by_key["default"][k] for k in keys])
        assert low["vs_default_difference_pp"] == pytest.approx(
            100 * (mine.mean() - ref.mean()), abs=0.01
        )
        assert (
            low["vs_default_ci_low_pp"]
            <= low["vs_default_difference_pp"]
            <= low["vs_default_ci_high_pp"]
        )
    # Planner a succeeds with p 0.1 against 0.8 at the default: a clear loss.
    assert q.loc[("low", "a"), "vs_default_verdict"] == "worse"
    assert q.loc[("low", "a"), "vs_default_p_value"] <= q.loc[("low", "a"), "vs_default_p_holm"]
    assert q.loc[("low", "a"), "vs_default_p_value"] < 0.05
    # sweep.md shows the same: the default marked, a's loss at "low" in bold with its p.
    md = (root / "sweep.md").read_text()
    assert "| default (default) |" in md
    [low_line] = [x for x in md.splitlines() if x.startswith("| low |")]
    a_cell = low_line.split(" | ")[1]
    assert a_cell.startswith(f"{q.loc[('low', 'a'), 'gsr_percent']:.1f} (") and "; **" in a_cell


def test_pile_points_carry_their_rates_and_pair_with_the_default(tmp_path, sweep):
    path = tmp_path / "pile.yaml"
    path.write_text(
        PROTOCOL
        + "pile: {objects: [mug, bowl, apple], rounds: 2, objects_per_round: 2, enabled: true}\n"
    )
    piled = replace(
        sweep,
        protocols=(SweepProtocol(str(path)),),
        experiments=("pile",),
        parameters=sweep.parameters[1:],
    )
    config = point_config(piled.protocols[0], piled)
    assert config.pile.enabled and not config.isolated.enabled and not config.packed.enabled
    run_sweep(piled, tmp_path / "sw", backend_factory=fake, progress=False)
    q = pd.read_csv(tmp_path / "sw" / CSV_FILE).set_index(["value", "planner"])
    assert set(q["experiment"]) == {"pile"}
    assert q.loc[("default", "a"), "objects_presented"] == 2 * 2 * 2  # seeds x rounds x objects
    low, default = q.loc[("low", "a")], q.loc[("default", "a")]
    assert low["vs_default_difference_pp"] == pytest.approx(
        low["cr_percent"] - default["cr_percent"], abs=0.01
    )
    assert (tmp_path / "sw" / "q.png").is_file()


def test_the_sweep_command_takes_pile_experiments():
    args = build_parser().parse_args(
        ["sweep", "--param", "p", "--values", "1", "--experiments", "pile"]
    )
    (adhoc,) = _sweeps(args)
    assert adhoc.experiments == ("pile",)


def _sweep_args(root, *more):
    return build_parser().parse_args(["sweep", "cameras", "--run", str(root), *more])


def test_a_sweep_folder_is_continued_only_with_resume_as_a_run_folder_is(tmp_path, sweep):
    from hsqbench.commands.sweep import _existing_sweep

    root = tmp_path / "sw"
    _existing_sweep(root, _sweep_args(root))  # nothing there yet: starts
    one = replace(sweep, parameters=sweep.parameters[:1], seeds=(0,))
    run_sweep(one, root, backend_factory=fake, progress=False)
    with pytest.raises(CommandError, match="already holds a sweep: pass --resume"):
        _existing_sweep(root, _sweep_args(root))
    with pytest.raises(CommandError, match="--retry-errors only applies with --resume"):
        _existing_sweep(root, _sweep_args(root, "--retry-errors"))
    _existing_sweep(root, _sweep_args(root, "--resume", "--retry-errors"))
    assert (root / SWEEP_FILE).is_file()
    _existing_sweep(root, _sweep_args(root, "--force"))
    assert not root.exists() and len(list(tmp_path.glob("sw.replaced-*"))) == 1


def test_report_writes_a_sweep_folders_report_and_the_old_switch_still_does(
    tmp_path, sweep, capsys
):
    from hsqbench.cli import main

    root = tmp_path / "sw"
    one = replace(sweep, parameters=sweep.parameters[:1], seeds=(0,))
    run_sweep(one, root, backend_factory=fake, progress=False)
    (root / CSV_FILE).unlink()
    assert main(["report", "--run", str(root)]) == 0
    assert (root / CSV_FILE).is_file() and "sweep report" in capsys.readouterr().out
    (root / CSV_FILE).unlink()
    assert main(["sweep", "--run", str(root), "--report-only"]) == 0
    assert (root / CSV_FILE).is_file()
    assert "--report-only is deprecated, use hsqbench report --run RUN" in capsys.readouterr().err
