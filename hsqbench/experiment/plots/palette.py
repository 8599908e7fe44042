"""One colour per planner and per attempt outcome, the same in every figure (report and sweeps).

The planners the repository ships keep a fixed colour, so hsq is the same blue in a run's
report, in another run's and in a sweep. Any other planner (an ablation, a user's own) takes
the next free colour in the order the figure's caller lists planners: callers pass the run's
full planner list, so every figure of one report agrees.
"""

from __future__ import annotations

#: Fixed colours of the shipped planners (matplotlib's tab10, then grey for the oracle, which
#: is a ceiling, not a method).
FIXED = {
    "hsq": "#1f77b4",
    "antipodal": "#ff7f0e",
    "single-sq": "#2ca02c",
    "contact-graspnet": "#d62728",
    "contact-graspnet-elim": "#9467bd",
    "hsq-paper": "#8c564b",
    "oracle": "#555555",
}
#: Colours for the remaining planners, in turn (tab10's rest, then tab20's light half).
SPARE = (
    "#e377c2",
    "#bcbd22",
    "#17becf",
    "#aec7e8",
    "#ffbb78",
    "#98df8a",
    "#ff9896",
    "#c5b0d5",
    "#c49c94",
    "#f7b6d2",
    "#dbdb8d",
    "#9edae5",
)
#: Hollow markers of the papers' reported rows are drawn in this colour.
REPORTED = "#222222"

#: Attempt outcomes (hsqbench.sim.outcome.Outcome) and harness faults, ``error`` (Tableau 10;
#: a planner's own error in brown, apart from the harness's black).
OUTCOME_COLOURS = {
    "success": "#59a14f",
    "no_grasp_found": "#bab0ac",
    "planner_error": "#9c755f",
    "unreachable": "#edc948",
    "collision_on_approach": "#e15759",
    "empty_grasp": "#f28e2b",
    "dropped": "#b07aa1",
    "sim_unstable": "#4e79a7",
    "error": "#222222",
}


def planner_colours(planners: list[str] | tuple[str, ...]) -> dict[str, str]:
    """Planner -> colour: the fixed one, else the next spare colour (cycling past the last)."""
    out = {p: FIXED[p] for p in planners if p in FIXED}
    others = [p for p in dict.fromkeys(planners) if p not in FIXED]
    out.update({p: SPARE[i % len(SPARE)] for i, p in enumerate(others)})
    return out
