"""Benchmark scenes: a table, the Panda at its back edge, a bin, two depth cameras and objects.

World frame = the Panda's base frame: origin at the base on the table top, x forward over the
table, y to the robot's left, z up. The table top is the plane z = 0. The static world (table,
bin, floor, lights, cameras) is MJCF in ``scenes/`` (:func:`load_world`); workspace and placement
rules come from ``configs/scene.yaml``; the robot from :mod:`hsqbench.sim.robot`; the physics
options from :mod:`hsqbench.sim.physics`.

Kinds:

- ``isolated``: one object, upright in its canonical pose with a random yaw, at a random position
  whose footprint lies inside the workspace.
- ``packed``: ``n_packed`` different objects, each upright with a random yaw, placed by rejection
  sampling so that no two footprints (rotated bounding rectangles grown by the margin) overlap.
- ``pile``: ``pile.n_objects`` different objects dropped one by one from random orientations
  into a box over the workspace centre, the box then removed (:mod:`hsqbench.sim.scene.pile`).

All are then settled (simulated with the arm holding its home pose) and the rest state is stored
as the keyframe ``initial``. Everything random comes from ``np.random.default_rng(seed)``.

Modules: :mod:`.config` (the scene config), :mod:`.info` (what a built scene holds),
:mod:`.footprint` and :mod:`.placement` (isolated and packed placement), :mod:`.pile` (the
drop) and :mod:`.pile_scene` (a pile as a scene), :mod:`.world` (composition and settling),
:mod:`.settled` (the compiled, settled scene), :mod:`.build` (:func:`build_scene`). Their public
names are re-exported here: ``from hsqbench.sim.scene import build_scene``.
"""

from hsqbench.sim.scene.build import build_scene, build_scene_spec
from hsqbench.sim.scene.config import (
    DepthCameraConfig,
    PileConfig,
    PlacementConfig,
    SceneConfig,
    ViewerCameraConfig,
    WorkspaceConfig,
    load_scene_config,
)
from hsqbench.sim.scene.footprint import (
    Footprint,
    footprint_corners,
    hull_vertices,
    min_area_rectangle,
    object_footprint,
    rectangles_overlap,
    rested_base_z,
)
from hsqbench.sim.scene.info import (
    BIN_GEOMS,
    INITIAL_KEY,
    KINDS,
    OBJECT_PREFIX,
    DepthCamera,
    SceneInfo,
)
from hsqbench.sim.scene.pile import PileDrop, PileError, drop_pile, heap_problem
from hsqbench.sim.scene.pile_scene import pile_placeable, settled_pile
from hsqbench.sim.scene.placement import (
    PlacementError,
    draw_object_names,
    draw_rests,
    layout_objects,
    packed_placeable,
    place_objects,
    resolve_scene_objects,
    scene_object_count,
)
from hsqbench.sim.scene.world import (
    compose_posed,
    compose_scene,
    describe_scene,
    load_world,
    settle,
    world_files,
    world_path,
)

__all__ = [
    "BIN_GEOMS",
    "INITIAL_KEY",
    "KINDS",
    "OBJECT_PREFIX",
    "DepthCamera",
    "DepthCameraConfig",
    "Footprint",
    "PileConfig",
    "PileDrop",
    "PileError",
    "PlacementConfig",
    "PlacementError",
    "SceneConfig",
    "SceneInfo",
    "ViewerCameraConfig",
    "WorkspaceConfig",
    "build_scene",
    "build_scene_spec",
    "compose_posed",
    "compose_scene",
    "describe_scene",
    "draw_object_names",
    "draw_rests",
    "drop_pile",
    "footprint_corners",
    "heap_problem",
    "hull_vertices",
    "layout_objects",
    "load_scene_config",
    "load_world",
    "min_area_rectangle",
    "object_footprint",
    "packed_placeable",
    "pile_placeable",
    "place_objects",
    "rectangles_overlap",
    "resolve_scene_objects",
    "rested_base_z",
    "scene_object_count",
    "settle",
    "settled_pile",
    "world_files",
    "world_path",
]
