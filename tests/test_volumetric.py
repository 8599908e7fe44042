"""The vgn and giga planners end to end on exact depth images of boxes on a table (needs torch
and the published weights: HSQ_MODELS_DIR, set by .ci/run)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from hsqbench.planner.api import PlanningContext
from hsqbench.planner.learned import volumetric, weights
from hsqbench.planner.learned.volumetric_config import resolve_volumetric_config
from hsqbench.planner.registry import planner_names, unavailable
from tests.volumetric_scene import BOX, TABLE, box_cloud, box_scene, planner_or_skip

pytestmark = pytest.mark.skipif(
    not volumetric.available(),
    reason="torch is not installed (the optional 'learned' extra: pip install -e '.[learned]')",
)


@pytest.fixture(scope="module", params=["vgn", "giga"])
def planner(request):
    return planner_or_skip(request.param)


def _context(boxes, scene="isolated", seed=0) -> PlanningContext:
    return PlanningContext(
        support_plane=TABLE, seed=seed, scene=scene, depth_views=box_scene(boxes)
    )


def test_registered_and_available():
    assert {"vgn", "giga"} <= set(planner_names())
    assert unavailable("vgn") is None and unavailable("giga") is None


def test_the_top_grasp_closes_across_the_box_not_on_the_table(planner):
    result = planner.plan(box_cloud([BOX]), _context([BOX]))
    assert result.grasps, result.reason
    best = result.grasps[0]
    lo, hi = BOX
    # P_G, midway between the pads, lies in the box, above the table.
    assert np.all(best.position > lo - 0.005) and np.all(best.position < hi + 0.005)
    assert best.position[2] > 0.01
    # The closing line through P_G crosses the box over less than the hand's 8 cm opening:
    # closing the fingers squeezes the box between them.
    with np.errstate(divide="ignore"):
        t0 = (lo - best.position) / best.closing_axis
        t1 = (hi - best.position) / best.closing_axis
    near, far = np.max(np.minimum(t0, t1)), np.min(np.maximum(t0, t1))
    assert near < 0 < far and far - near < 0.08
    assert 0.0133 * 0.75 <= best.width <= 0.0933 * 0.75
    assert result.timings["network"] > 0 and result.timings["total"] >= result.timings["tsdf"]
    assert len(result.surface_points) > 500


def test_same_observation_same_grasps_whatever_the_seed(planner):
    first = planner.plan(box_cloud([BOX]), _context([BOX], seed=1))
    again = planner.plan(box_cloud([BOX]), _context([BOX], seed=1))
    other = planner.plan(box_cloud([BOX]), _context([BOX], seed=7))
    for result in (again, other):
        assert [g.to_dict() for g in result.grasps] == [g.to_dict() for g in first.grasps]


def test_a_wide_scene_is_tiled_and_every_box_gets_grasps(planner):
    """Two boxes 0.40 m apart (more than one 0.30 m cube): each is covered by a cube, in each
    camera's input (the two cameras' yawed frames both need two cubes across the boxes)."""
    left = (BOX[0] + [0, -0.2, 0], BOX[1] + [0, -0.2, 0])
    right = (BOX[0] + [0, 0.2, 0], BOX[1] + [0, 0.2, 0])
    result = planner.plan(box_cloud([left, right]), _context([left, right], scene="packed"))
    assert result.remaining["cubes"] == 2 * 2
    ys = np.array([g.position[1] for g in result.grasps])
    assert np.any(ys < -0.1) and np.any(ys > 0.1)  # grasps near each box
    positions = np.array([g.position for g in result.grasps])
    assert len(np.unique(positions.round(4), axis=0)) == len(positions)  # none from two cubes


def test_piles_use_the_pile_weights(planner):
    cloud = box_cloud([BOX])
    packed = planner.plan(cloud, _context([BOX], scene="packed"))
    pile = planner.plan(cloud, _context([BOX], scene="pile"))
    swapped = dataclasses.replace(
        planner.config, weights={"isolated": "pile", "packed": "pile", "pile": "pile"}
    )
    as_pile = type(planner)(planner.network, swapped).plan(cloud, _context([BOX], scene="packed"))
    assert [g.to_dict() for g in as_pile.grasps] == [g.to_dict() for g in pile.grasps]
    assert [g.to_dict() for g in packed.grasps] != [g.to_dict() for g in pile.grasps]


def test_without_depth_images_or_table_the_error_says_what_is_missing(planner):
    with pytest.raises(ValueError, match="depth images"):
        planner.plan(box_cloud([BOX]), PlanningContext(support_plane=TABLE))
    views = box_scene([BOX])
    with pytest.raises(ValueError, match="table plane"):
        planner.plan(box_cloud([BOX]), PlanningContext(depth_views=views))


def test_cubes_cover_the_footprint_with_their_kept_parts():
    cfg = resolve_volumetric_config(None)
    plane = np.array(TABLE)
    one, _ = volumetric.cube_origins(box_cloud([BOX]), plane, cfg)
    assert one.shape == (1, 3) and one[0, 2] == pytest.approx(-cfg.grid.table_height_m)
    wide = np.array([[0.32, -0.25, 0.05], [0.68, 0.25, 0.05]])
    origins, centres = volumetric.cube_origins(wide, plane, cfg)
    assert len(origins) == 2 * 2
    voxel = cfg.grid.voxel_m
    kept_lo = origins[:, :2] + 2 * voxel  # the 2 cm bounds: voxels 0 and 1 are cut
    kept_hi = origins[:, :2] + 37 * voxel
    for corner in ([0.32, -0.25], [0.68, 0.25], [0.5, 0.0]):
        inside = np.all(
            (kept_lo <= np.add(corner, 1e-9)) & (np.subtract(corner, 1e-9) <= kept_hi), axis=1
        )
        assert inside.any(), corner
    assert np.allclose(centres, 0.5 * (kept_lo + kept_hi))


def test_quaternions_become_harness_grasp_frames():
    # The identity: the networks' y closes, z approaches.
    frame = volumetric.grasp_frames(np.array([[0.0, 0.0, 0.0, 1.0]]))[0]
    assert np.allclose(frame, [[0, -1, 0], [1, 0, 0], [0, 0, 1]])
    # 180 deg about x: approach straight down, closing along -y.
    frame = volumetric.grasp_frames(np.array([[1.0, 0.0, 0.0, 0.0]]))[0]
    assert np.allclose(frame[:, 2], [0, 0, -1]) and np.allclose(frame[:, 0], [0, -1, 0])
    assert np.isclose(np.linalg.det(frame), 1.0)


@pytest.mark.slow
def test_a_benchmark_run_reports_their_planning_time(planner, tmp_path):
    """One simulated trial of each through the benchmark runner: the planner's wall time per
    observation lands in planning_time.csv, as every planner's does."""
    import pandas as pd

    from hsqbench.experiment.config import ExperimentConfig, IsolatedConfig
    from hsqbench.experiment.report import TIMES_CSV, write_report
    from hsqbench.experiment.runner import run_benchmark

    config = ExperimentConfig(
        planners=(planner.name,),
        isolated=IsolatedConfig(objects=("proc_box",), attempts_per_object=1),
    )
    run_benchmark(config, tmp_path / "run", experiments=("isolated",), progress=False)
    write_report(tmp_path / "run")
    times = pd.read_csv(tmp_path / "run" / TIMES_CSV)
    attempts = pd.read_csv(tmp_path / "run" / "attempts.csv")
    row = times[(times["planner"] == planner.name) & (times["experiment"] == "isolated")]
    assert len(row) == 1 and row["n"].iloc[0] == len(attempts) >= 1
    assert row["median_s"].iloc[0] == pytest.approx(attempts["planning_s"].median())
    assert 0 < row["median_s"].iloc[0] < 60


def test_the_other_weights_pairing_example_swaps_the_weights():
    """examples/other_weights: a plugin planner whose config extends the shipped one."""
    from hsqbench.planner.plugins import factory, load_spec
    from hsqbench.settings import REPO_ROOT

    obj, source = load_spec(f"{REPO_ROOT}/examples/other_weights/swapped.py:GIGASwapped")
    try:
        planner = factory(obj, "giga-swapped")()
    except weights.WeightsError as exc:
        pytest.skip(f"the published weights are not here ({exc}); set HSQ_MODELS_DIR")
    assert planner.name == "giga-swapped" and source.kind == "file"
    assert planner.config.weights == {"isolated": "pile", "packed": "pile", "pile": "packed"}
    assert planner.config.grid == resolve_volumetric_config(None).grid
