"""``hsqbench report RUN_DIR``: tables and plots of a run, from its results files alone."""

from __future__ import annotations

import argparse
from pathlib import Path

HELP = "write tables.md, table CSVs and PNG plots of a benchmark run from its results files"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("run_dir", type=Path, help="the run folder, e.g. runs/paper-20250101")
    parser.add_argument(
        "--with",
        dest="with_runs",
        nargs="+",
        type=Path,
        default=(),
        metavar="RUN_DIR",
        help="other runs of the same protocol and seeds whose further planners join the tables",
    )
    parser.add_argument(
        "--reference",
        default=None,
        metavar="PLANNER",
        help="the planner every other is compared with on the same presentations (paired "
        "section of tables.md; default hsq)",
    )


def run(args: argparse.Namespace) -> int:
    from hsqbench.experiment.report import write_report

    if not args.run_dir.is_dir():
        raise FileNotFoundError(f"{args.run_dir} is not a folder; give runs/<run>")
    for path in write_report(args.run_dir, tuple(args.with_runs), args.reference):
        print(path)
    return 0
