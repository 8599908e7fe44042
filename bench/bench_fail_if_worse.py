"""How often ``compare --fail-if-worse`` fails a change that changes nothing but the dice.

Simulates changes that re-roll every outcome at random: eight planners at ``results/ycb3``'s
rates, each with 1,170 isolated pairs and 45 rounds of 5 objects, B drawn independently of A at
A's rate. A change "fails" when some planner's B is judged worse. Old rule: any of the 16 tests
at p < 0.05 unadjusted, CR by McNemar over the objects of the rounds. Current rule (compare):
Holm over the 16 tests, CR by the exact sign-flip test over rounds.

    .venv/bin/python bench/bench_fail_if_worse.py [--changes 2000] [--seed 0]
"""

from __future__ import annotations

import argparse

import numpy as np

#: ycb3's isolated GSR and packed CR per planner (README, Table III), as fractions.
GSR = (0.771, 0.542, 0.488, 0.736, 0.622, 0.323, 0.468, 0.657)
CR = (0.787, 0.587, 0.347, 0.782, 0.613, 0.218, 0.276, 0.724)
PRESENTATIONS, ROUNDS, PER_ROUND = 1170, 45, 5


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--changes", type=int, default=2000, help="simulated changes")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()

    from hsqbench.experiment.holm import holm
    from hsqbench.experiment.paired import mcnemar_exact
    from hsqbench.experiment.sign_flip import sign_flip_p

    rng = np.random.default_rng(args.seed)
    old = new = 0
    for _ in range(args.changes):
        unadjusted, current, diffs = [], [], []
        for g, c in zip(GSR, CR, strict=True):
            a, b = rng.random(PRESENTATIONS) < g, rng.random(PRESENTATIONS) < g
            won, lost = int((b & ~a).sum()), int((a & ~b).sum())
            p = mcnemar_exact(won, lost)
            unadjusted.append(p)
            current.append(p)
            diffs.append(won - lost)
            ra, rb = rng.random((ROUNDS, PER_ROUND)) < c, rng.random((ROUNDS, PER_ROUND)) < c
            won, lost = int((rb & ~ra).sum()), int((ra & ~rb).sum())
            unadjusted.append(mcnemar_exact(won, lost))
            current.append(sign_flip_p(rb.sum(axis=1).astype(int) - ra.sum(axis=1).astype(int)))
            diffs.append(won - lost)
        d = np.array(diffs)
        old += bool(np.any((np.array(unadjusted) < 0.05) & (d < 0)))
        new += bool(np.any((holm(np.array(current)) < 0.05) & (d < 0)))
    print(
        f"{args.changes} re-rolled changes fail --fail-if-worse: unadjusted "
        f"{100 * old / args.changes:.1f} %, Holm over rounds and presentations "
        f"{100 * new / args.changes:.1f} %"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
