"""Objects of a packed scene (hsqbench.planner.hsq.stage_one.clusters), and hsq's stage one on each of them."""

from __future__ import annotations

import numpy as np
import pytest

from hsqbench.config import from_dict
from hsqbench.errors import ConfigError
from hsqbench.planner.api import PlanningContext
from hsqbench.planner.hsq.config import PlannerConfig, RecoveryConfig
from hsqbench.planner.hsq.planner import HSQPlanner, plan_grasps
from hsqbench.planner.hsq.stage_one.clusters import object_clusters
from tests.planner.baselines.test_baselines import CAMERAS, TABLE, two_boxes_apart


def test_object_clusters_split_objects_placed_apart() -> None:
    a, b, points = two_boxes_apart()
    groups = object_clusters(points, RecoveryConfig())
    assert len(groups) == 2
    for group in groups:
        on_a = a.contains(points[group], tol=0.005)
        on_b = b.contains(points[group], tol=0.005)
        assert on_a.all() or on_b.all()
    # The three strays are too few for an object; so is a lone sample the views caught at a
    # box's bottom edge, but (nearly) every box point is in a cluster.
    clustered = np.zeros(len(points), dtype=bool)
    clustered[np.concatenate(groups)] = True
    assert not clustered[-3:].any() and clustered[:-3].mean() > 0.999
    # Linked at 4 cm, the 3 cm gap no longer separates them.
    wide = RecoveryConfig(cluster_distance_m=0.04)
    assert len(object_clusters(points, wide)) == 1


def test_cluster_settings_are_checked() -> None:
    with pytest.raises(ConfigError, match="cluster_voxel_m"):
        from_dict(PlannerConfig, {"recovery": {"cluster_voxel_m": 0.02}})
    with pytest.raises(ConfigError, match="min_cluster_points"):
        from_dict(PlannerConfig, {"recovery": {"min_cluster_points": 5}})


def _spans(hidden, points: np.ndarray, a, b) -> list[bool]:
    """Per hidden superquadric: do its inliers hold points of both boxes?"""
    out = []
    for h in hidden:
        inl = points[h.inliers]
        out.append(bool(a.contains(inl, tol=0.005).any() and b.contains(inl, tol=0.005).any()))
    return out


def test_hsq_recovers_each_object_of_a_packed_scene_on_its_own() -> None:
    a, b, points = two_boxes_apart()
    packed = plan_grasps(points, packed=True, support_plane=TABLE, seed=0, camera_positions=CAMERAS)
    assert packed.grasps, packed.reason
    hidden = packed.hidden_superquadrics
    # Two whole-object fits (seed 0), one per box, and no superquadric explains both boxes.
    wholes = [h for h in hidden if h.seed == 0]
    assert len(wholes) == 2
    assert not any(_spans(hidden, points, a, b))
    for box, whole in zip(
        (a, b), sorted(wholes, key=lambda h: h.superquadric.translation[1]), strict=True
    ):
        assert np.allclose(whole.superquadric.translation, box.center, atol=0.01)
        assert np.allclose(np.sort(whole.superquadric.scale), [0.02, 0.03, 0.05], atol=0.006)
    # Inliers index the cloud as given (the strays are cleaned away but not renumbered).
    assert all(
        a.contains(points[h.inliers], tol=0.005).all()
        or b.contains(points[h.inliers], tol=0.005).all()
        for h in hidden
    )


@pytest.mark.parametrize("how", ["isolated", "switch off"])
def test_without_the_split_the_scene_is_one_cloud(how: str) -> None:
    a, b, points = two_boxes_apart()
    context = PlanningContext(
        support_plane=TABLE, packed=how == "switch off", seed=0, camera_positions=CAMERAS
    )
    planner = HSQPlanner(additions_off=("object_split",) if how == "switch off" else ())
    hidden = planner.plan(points, context).hidden_superquadrics
    # One whole-scene fit, around both boxes.
    wholes = [h for h in hidden if h.seed == 0]
    assert len(wholes) == 1 and _spans(wholes, points, a, b) == [True]
