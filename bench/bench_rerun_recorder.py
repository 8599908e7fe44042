"""Cost of recording an episode with Rerun (`--rerun`): time and file size.

Runs the same isolated trial alternately without and with a `RerunRecorder` (in one process, so
imports and the object build are paid before timing), and reports the median wall and CPU time
of each (CPU time counts Rerun's encoder threads too), the time spent inside the recorder's
callbacks, and the file size. `--packed` also records one packed round (file size of a round).

    .venv/bin/python bench/bench_rerun_recorder.py [--object proc_box] [--repeats 3] [--packed]
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time
from collections import defaultdict
from pathlib import Path

CALLBACKS = ("on_scene", "on_observation", "on_plan", "on_grasp", "on_step", "on_outcome")


def _timed_recorder(path: Path, totals: dict[str, float]):
    from hsqbench.viz.rerun_recorder import RerunRecorder

    class Timed(RerunRecorder):
        pass

    for name in (*CALLBACKS, "close"):
        method = getattr(RerunRecorder, name)

        def wrapper(self, *args, _method=method, _name=name):
            start = time.perf_counter()
            try:
                return _method(self, *args)
            finally:
                totals[_name] += time.perf_counter() - start

        setattr(Timed, name, wrapper)
    return Timed(path)


def _run(fn) -> tuple[float, float, object]:
    wall, cpu = time.perf_counter(), time.process_time()
    out = fn()
    return time.perf_counter() - wall, time.process_time() - cpu, out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--object", default="proc_box")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--packed", action="store_true", help="also record one packed round")
    args = parser.parse_args()

    from hsqbench.sim.trial import run_isolated_trial, run_packed_round
    from hsqbench.viz.rerun_recorder import RerunRecorder

    with tempfile.TemporaryDirectory(prefix="hsq-bench-rerun-") as tmp:
        run_isolated_trial(args.object, args.seed)  # warm-up: imports, object build, caches
        plain, recorded, sizes = [], [], []
        totals: dict[str, float] = defaultdict(float)
        for k in range(args.repeats):
            plain.append(_run(lambda: run_isolated_trial(args.object, args.seed))[:2])
            path = Path(tmp) / f"trial{k}.rrd"

            def with_recorder(path=path):
                rec = _timed_recorder(path, totals)
                try:
                    return run_isolated_trial(args.object, args.seed, recorder=rec)
                finally:
                    rec.close()

            recorded.append(_run(with_recorder)[:2])
            sizes.append(os.path.getsize(path))
        n = args.repeats
        med = [statistics.median(x) for x in zip(*plain, strict=True)]
        med_rec = [statistics.median(x) for x in zip(*recorded, strict=True)]
        print(f"isolated trial {args.object} seed {args.seed}, {n} repeats (median):")
        print(f"  without recorder: {med[0]:6.2f} s wall  {med[1]:6.2f} s cpu")
        print(f"  with recorder:    {med_rec[0]:6.2f} s wall  {med_rec[1]:6.2f} s cpu")
        print(
            f"  overhead:         {med_rec[0] - med[0]:+6.2f} s wall  {med_rec[1] - med[1]:+6.2f} s cpu"
        )
        inside = ", ".join(f"{k} {v / n * 1000:.0f} ms" for k, v in totals.items())
        print(f"  inside the recorder per trial: {sum(totals.values()) / n:.2f} s ({inside})")
        print(f"  file size: {statistics.median(sizes) / 1e6:.2f} MB")
        if args.packed:
            path = Path(tmp) / "packed.rrd"
            with RerunRecorder(path) as rec:
                wall, _, result = _run(lambda: run_packed_round(None, args.seed, recorder=rec))
            print(
                f"packed round seed {args.seed} ({', '.join(result.objects)}): "
                f"{len(result.attempts)} attempts, {wall:.1f} s, file {os.path.getsize(path) / 1e6:.2f} MB"
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
