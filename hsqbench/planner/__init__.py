"""Grasp planners behind one contract, and the learning-free planner of the paper.

The contract every planner shares: :mod:`.api` (:class:`Planner`, :class:`PlanningContext`,
:class:`PlanResult`, input checks), :mod:`.base` (the front door: validate, clean, time),
:mod:`.registry` (planners by name), :mod:`.grasp`, :mod:`.gripper`, :mod:`.cleaning`.
The planners: :mod:`.hsq` (the paper's, in two stages: :mod:`.hsq.stage_one` recovers hidden
superquadrics from a point cloud, :mod:`.hsq.stage_two` turns them into ranked antipodal
grasps), :mod:`.baselines`, :mod:`.learned` and :mod:`.oracle`. The whole hsq planner is
:func:`hsqbench.planner.hsq.planner.plan_grasps`; harness code talks to any planner through
:class:`hsqbench.planner.api.Planner`, found by name in :mod:`.registry`. Import each name from
the module that defines it: this package exports nothing, so one stage never imports another.
"""
