"""Top-down grasps at the cloud's centroid in 12 closing directions, through the harness's
elimination rules (opted into with ``apply_rules``), the narrowest first."""

import numpy as np

from hsqbench.planner.base import PlannerBase
from hsqbench.planner.grasp import Grasp


class TopDownRules(PlannerBase):
    name = "topdown-rules"  # as the entry point names it

    def stages(self, clean, context):
        points = clean.points  # (N, 3) world metres, table removed, cleaned as hsq's input
        centre = points.mean(axis=0)
        top, bottom = points[:, 2].max(), points[:, 2].min()
        position = np.array([*centre[:2], max(top - 0.03, (top + bottom) / 2)])
        angles = np.linspace(0.0, np.pi, 12, endpoint=False)
        closing = np.column_stack([np.cos(angles), np.sin(angles), np.zeros(12)])
        widths = np.ptp(points @ closing.T, axis=0)  # the cloud's extent along each direction
        approach = np.array([0.0, 0.0, -1.0])  # from the palm toward the grasp point: down
        grasps = [
            Grasp(
                position, np.column_stack([c, np.cross(approach, c), approach]), w, widths.min() / w
            )
            for c, w in zip(closing, widths, strict=True)
        ]
        # Width, support, table, collision and approach sweep, as hsq's candidates get them.
        return self.apply_rules(grasps, clean, context)
