"""The trial runner: perceive, plan, and execute grasps with the Panda in a MuJoCo scene.

One attempt (:func:`run_attempt`):

1. **Perceive** the fused cloud (the two depth cameras of :mod:`hsqbench.sim.perception`, or the
   fast :mod:`hsqbench.sim.surface_sensor` stand-in), with the arm at home, out of view.
2. **Plan** with the planner (``PlanningContext``: table plane, ``packed``, seed, cameras,
   workspace). No grasp: ``no_grasp_found``. The planner raised, or returned what its contract
   rules out (not a PlanResult, an invalid grasp): ``planner_error``, with the planner's file
   and line in ``detail`` (:mod:`hsqbench.planner.failure`); a failed attempt like the first.
3. **Motion plan** (IK, :mod:`hsqbench.sim.ik`) the grasps in score order, equal scores (the
   rolls of one closing line) with the most easily reached approach first, up to ``max_ranks``
   distinct grasps. For each grasp and its twin turned by pi about the approach axis (the same
   parallel-jaw grasp): solve the grasp pose (restarts; branches nearest the current posture
   first), then outward from it the straight approach line back to the pre-grasp
   (``pregrasp_distance_m`` along the approach axis), the vertical line up to a hover pose when
   the pre-grasp is low (so the joint-space move ends above the objects), the vertical lift and
   the carry pose above the bin. The motion must keep the arm off the table and bin all along
   and, on the way in, out of the perceived cloud. Of the twins the one with the shorter
   joint-space move is executed. None executable: ``unreachable``.
4. **Execute** (:mod:`hsqbench.sim.motion`): joint-space move to the hover pose or pre-grasp;
   vertical descent; straight approach; close with the 70 N hand; lift; carry (mostly a turn of
   the base joint) above the bin; lower; open. The carry and the lowering are re-solved for where
   the object really is in the hand and checked as the approach was (no robot part too near the
   table or bin along them): a carry that fails the check is replaced by the planned one (the
   grasp point, not the object's centre, over the bin) when that passes the check from where
   the arm is, and the detail says so, else it ends the attempt as ``unreachable`` with the
   object held; a lowering that fails
   it is moved away from a sideways wrist, made shorter or not run, the hand opens over the bin
   from higher up, and the detail says so; an object lost during the lowering is released where
   it is; an object not in the bin once the hand is open (hanging on a finger) is freed by
   withdrawing the hand along its approach before it is judged. The phases are
   :data:`~hsqbench.sim.trial.execution.PHASES`. Judged on the way (:mod:`hsqbench.sim.judge`):

   - ``collision_on_approach``: before the fingers close, the robot presses the table or bin
     (``table_contact_force_n``), or pushes an object (``object_contact_force_n``) farther than
     ``pushed_distance_m``. The motion stops there.
   - ``empty_grasp``: after closing, the fingers are closed (``empty_width_m``) or no object
     touches both fingers; or the object is lost during the lift before it rose
     ``lifted_height_m``.
   - ``dropped``: the object was lifted, then left a finger for ``lost_time_s`` or slipped
     ``slip_distance_m`` in the hand (at the point held between the pads) before the lowering
     into the bin; or it was released (or lost while lowered) but did not come to rest inside
     the bin.
   - ``success``: held from the lift to the bin, and at rest inside the bin afterwards (the
     paper: "grasps the object and moves it from the workspace to a bin next to the arm without
     dropping it").
   - ``sim_unstable``: NaN or exploding state at any point (never a success).

Isolated trial (:func:`run_isolated_trial`): one object at a seeded random upright pose, one
attempt. Packed round (:func:`run_packed_round`): the paper's rule, attempts until no object is
left on the table or two consecutive failures; after each attempt the hand opens, the arm goes
home, and objects in the bin (cleared) or out of the workspace (off the table or out of the
cameras' view: not cleared) are taken out of the scene.

Determinism: everything random comes from ``seed`` (scene layout, sensor noise and calibration,
planner seed, IK restarts, each from its own ``SeedSequence`` stream) and MuJoCo is deterministic,
so the same seed and config give the same outcomes and numbers (timings aside). Planners that
meet the same presentation one after another in a process share its built scene and first look
(:mod:`hsqbench.sim.trial.presentation`), with the same outcomes as building it each time.

Where the runner uses simulator truth rather than what the robot perceives: the judge (as any
simulated benchmark) and the names in the records (``target``: the object held, or nearest the
grasp); and, after the lift, the held object's position and lowest point, used to centre it over
the bin and lower it before release (a real robot would use a conservative fixed height). The
lift height is not: objects start on the table, so the lift that brings their bottom over the
bin walls follows from the table and bin alone.
"""

from hsqbench.sim.trial.attempt import AttemptTrace, MotionPlan, resolve_planner, run_attempt
from hsqbench.sim.trial.config import (
    ExecutionConfig,
    PackedConfig,
    TrialConfig,
    load_trial_config,
    named_inputs,
)
from hsqbench.sim.trial.env import TrialEnv
from hsqbench.sim.trial.execution import ExecutionResult, execute_grasp
from hsqbench.sim.trial.planning import GraspMotion, plan_grasp_motion, plan_motion
from hsqbench.sim.trial.protocols import run_isolated_trial, run_packed_round

__all__ = [
    "AttemptTrace",
    "ExecutionConfig",
    "ExecutionResult",
    "GraspMotion",
    "MotionPlan",
    "PackedConfig",
    "TrialConfig",
    "TrialEnv",
    "execute_grasp",
    "load_trial_config",
    "named_inputs",
    "plan_grasp_motion",
    "plan_motion",
    "resolve_planner",
    "run_attempt",
    "run_isolated_trial",
    "run_packed_round",
]
