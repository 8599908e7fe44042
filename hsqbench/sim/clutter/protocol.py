"""VGN/GIGA's clutter-removal round (docs/clutter-removal.md): their scene generated, then
executed by the free hand (:mod:`hsqbench.sim.clutter.round`) or, for the bridge, by the
harness's arm (:mod:`hsqbench.sim.clutter.arm`), as the trial config's ``clutter.executor``
says."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from hsqbench.sim.clutter.scenes import build_clutter_scene
from hsqbench.sim.objects import ObjectLike
from hsqbench.sim.outcome import RoundResult


def run_clutter_round(
    objects: Sequence[str | ObjectLike],
    seed: int,
    planner: Any,
    config: Any,
    kind: str = "packed",
) -> RoundResult:
    """A round of VGN/GIGA's clutter removal with ``planner`` (a name or a planner) under the
    trial config ``config`` whose ``clutter`` is set (its robot hand, physics and planners)."""
    clutter = config.clutter
    if clutter is None:
        raise ValueError("run_clutter_round needs a trial config with clutter: set")
    world = build_clutter_scene(kind, objects, seed, clutter, config.robot, config.physics)
    if clutter.executor == "arm":
        from hsqbench.sim.clutter.arm import run_arm_round

        return run_arm_round(world, kind, seed, planner, config)
    from hsqbench.sim.clutter.round import run_hand_round

    return run_hand_round(world, kind, seed, planner, config)
