"""A complete planner for hsqbench: one top-down grasp at the cloud's centroid.

hsqbench trial --planner examples/topdown.py:TopDown --object foam_brick
hsqbench benchmark --protocol quick --planners examples/topdown.py:TopDown hsq --jobs 2
"""

import numpy as np

from hsqbench.planner.api import PlanResult
from hsqbench.planner.base import PlannerBase
from hsqbench.planner.grasp import Grasp


class TopDown(PlannerBase):
    """Close across the cloud's narrowest horizontal direction, from straight above."""

    name = "topdown"  # the planner's name in results and tables

    def stages(self, clean, context):
        points = clean.points  # (N, 3) world metres, table removed, cleaned as hsq's input
        centre = points.mean(axis=0)
        spread = np.cov((points[:, :2] - centre[:2]).T)
        closing = np.append(np.linalg.eigh(spread)[1][:, 0], 0.0)  # minor horizontal axis
        approach = np.array([0.0, 0.0, -1.0])  # from the palm toward the grasp point: down
        rotation = np.column_stack([closing, np.cross(approach, closing), approach])
        top, bottom = points[:, 2].max(), points[:, 2].min()
        position = np.array([*centre[:2], max(top - 0.03, (top + bottom) / 2)])
        width = float(np.ptp(points @ closing))  # the cloud's extent between the pads
        grasp = Grasp(position, rotation, width=width, score=1.0)
        return PlanResult(grasps=[grasp])
