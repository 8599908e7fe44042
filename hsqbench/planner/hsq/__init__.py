"""The paper's planner, hsq, laid out as the paper's Sec. III.

- :mod:`.stage_one`: hidden superquadric recovery (Sec. III-A).
- :mod:`.stage_two`: grasp synthesis, elimination and evaluation (Sec. III-B).
- :mod:`.planner`: :class:`~hsqbench.planner.hsq.planner.HSQPlanner` and
  :func:`~hsqbench.planner.hsq.planner.plan_grasps`, the two stages behind the shared
  :class:`~hsqbench.planner.api.Planner` protocol.
- :mod:`.config`: ``configs/planner.yaml`` as typed dataclasses; :mod:`.additions`: the switches
  of our additions to the paper (each off gives the paper's method).
"""
