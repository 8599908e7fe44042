"""hsqbench from Python, as a notebook would drive it: one trial, a benchmark, its tables.

    python examples/notebook_api.py [RUN]

Runs the example planner (examples/topdown.py) on the quick protocol's isolated objects (two
objects, one pose each) with two worker processes, then analyses the run with pandas.
"""

import sys
from pathlib import Path

import hsqbench

TOPDOWN = str(Path(__file__).with_name("topdown.py")) + ":TopDown"

# One trial: the result holds each attempt's outcome, grasp and timings.
trial = hsqbench.run_trial("foam_brick", planner=TOPDOWN, seed=0)
print(f"trial: {trial.object} -> {trial.attempts[0].outcome.value}")

# A benchmark: the protocol's scenes for our planner (add "hsq" to compare), into a run folder.
run_dir = sys.argv[1] if len(sys.argv) > 1 else "runs/notebook-example"
run = hsqbench.run_benchmark(
    "quick", planners=[TOPDOWN], run=run_dir, experiments=["isolated"], jobs=2, resume=True
)

# The run as pandas frames: one row per attempt (and per packed round in run.rounds).
attempts = run.attempts
print(attempts.groupby("planner")["success"].agg(["mean", "count"]))
print(attempts.pivot_table(index="objects", columns="planner", values="planning_s"))
print(f"protocol {run.meta['config_name']}, config hash {run.meta['config_hash']}")

# Any run folder loads the same way, e.g. one made by `hsqbench benchmark`.
again = hsqbench.load_run(run_dir)
assert len(again.attempts) == len(attempts)
