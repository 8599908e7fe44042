"""The clutter-removal rounds' stop rule (packed and pile), in one place: the trial runner
applies it, the fake backend mimics it, and the report checks recorded rounds against it.

The paper's rule: a round goes on until no object is left on the table or two consecutive
failures. The harness adds a cap on attempts, and a round also ends when the simulation becomes
unstable (nothing after that can be trusted). VGN and GIGA also end a round at the first attempt
without a grasp (``stop_on_no_grasp``; off by default, so Tables II and IV share the paper's rule).
A planner's own error (``planner_error``) is an attempt without a grasp: a failure in the count
of consecutive failures, and where ``stop_on_no_grasp`` holds, the end of the round.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

#: The outcome (its value in the records) that ends a round at once.
SIM_UNSTABLE = "sim_unstable"
SUCCESS = "success"
NO_GRASP_FOUND = "no_grasp_found"
PLANNER_ERROR = "planner_error"
#: The outcomes of an attempt whose planner gave no grasp to execute.
NO_GRASP = (NO_GRASP_FOUND, PLANNER_ERROR)


@dataclass(frozen=True)
class PackedConfig:
    """The stop rule (``packed:`` and ``pile:`` in ``configs/trial.yaml``): stop after
    ``max_consecutive_failures`` failures in a row (the paper: two) or ``max_attempts``
    attempts (a cap that the rule reaches first in practice), and with ``stop_on_no_grasp`` at
    the first attempt whose planner found no grasp (or failed: ``planner_error``)."""

    max_consecutive_failures: int = 2
    max_attempts: int = 15
    stop_on_no_grasp: bool = False

    def __post_init__(self) -> None:
        if self.max_consecutive_failures < 1 or self.max_attempts < 1:
            raise ValueError("packed: max_consecutive_failures and max_attempts must be >= 1")

    def stop_reason(self, outcomes: Sequence[str], objects_left: bool) -> str | None:
        """Why a round whose attempts so far had ``outcomes`` (in order) ends now, or None when
        it goes on. ``objects_left``: objects remain on the table."""
        if not objects_left:
            return "the table is clear"
        if outcomes and outcomes[-1] == SIM_UNSTABLE:
            return "the simulation became unstable"
        if self.stop_on_no_grasp and outcomes and outcomes[-1] in NO_GRASP:
            return "no grasp found"
        if len(outcomes) >= self.max_attempts:
            return f"{self.max_attempts} attempts (the cap)"
        tail = outcomes[-self.max_consecutive_failures :]
        if len(tail) == self.max_consecutive_failures and SUCCESS not in tail:
            return f"{self.max_consecutive_failures} consecutive failures"
        return None

    def ended_early(self, outcomes: Sequence[str], objects_left: bool) -> bool:
        """Whether a recorded round stopped although the rule says it should have gone on
        (objects left, and none of the rule's reasons to stop)."""
        return self.stop_reason(outcomes, objects_left) is None
