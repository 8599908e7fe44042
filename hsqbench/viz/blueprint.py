"""The default layout of an episode in the Rerun viewer (a ``rerun.blueprint``).

The 3-D scene on the left, seen from the side of the depth camera whose name sorts first
(``left`` of ``left`` and ``right``; pulled back by
:data:`EYE_PULLBACK` so the arm and the bin are in view, looking at the middle of the
workspace's floor); beside it each camera's depth image, the attempt's outcome, the event log
and the gripper width. The recorder sends it with every recording, and ``hsqbench view`` serves
it beside the recording as an ``.rbl`` file (the web viewer opens a recording on the blueprint
given with it), built from what the recording holds, so recordings made before it open on it
too.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

#: The recordings' Rerun application id: a blueprint applies to recordings of the same id.
APPLICATION_ID = "hsqbench"
#: The eye sits this many times the first camera's distance from the target, on its line.
EYE_PULLBACK = 1.5


def eye_position(camera_m: ArrayLike, target_m: ArrayLike) -> np.ndarray:
    """Where the 3-D view's eye goes: on the line from ``target_m`` through the camera at
    ``camera_m``, :data:`EYE_PULLBACK` times as far (metres, world frame)."""
    target = np.asarray(target_m, dtype=float)
    return target + EYE_PULLBACK * (np.asarray(camera_m, dtype=float) - target)


def episode_blueprint(
    camera_names: Sequence[str],
    camera_m: ArrayLike | None = None,
    target_m: ArrayLike | None = None,
) -> Any:
    """The episode layout (see the module docstring). ``camera_m``: the position of the camera
    named first of ``camera_names`` (sorted),
    ``target_m``: the point the scene view looks at; without them the viewer's own eye."""
    import rerun.blueprint as rrb

    eye = None
    if camera_m is not None and target_m is not None:
        eye = rrb.EyeControls3D(
            position=eye_position(camera_m, target_m),
            look_target=np.asarray(target_m, dtype=float),
            eye_up=[0.0, 0.0, 1.0],
        )
    depth_views = [
        rrb.Spatial2DView(origin=f"world/cameras/{c}", name=f"{c} depth") for c in camera_names
    ]
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Spatial3DView(
                origin="world",
                name="scene",
                contents=["+ world/**", "- world/**/collision_geoms"],
                eye_controls=eye,
            ),
            rrb.Vertical(
                *depth_views,
                rrb.TextDocumentView(origin="outcome", name="outcome"),
                rrb.TextLogView(origin="events", name="events"),
                rrb.TimeSeriesView(origin="plots", name="gripper width (m)"),
            ),
            column_shares=[3, 2],
        ),
        collapse_panels=True,
    )


def save_blueprint(blueprint: Any, path: str | Path) -> Path:
    """Write ``blueprint`` as an ``.rbl`` file for recordings of :data:`APPLICATION_ID`."""
    path = Path(path)
    blueprint.save(APPLICATION_ID, str(path))
    return path
