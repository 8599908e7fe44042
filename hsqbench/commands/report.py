"""``hsqbench report --run RUN``: tables and plots of a run, from its results files alone."""

from __future__ import annotations

import argparse
from pathlib import Path

from hsqbench.commands._deprecated import deprecated
from hsqbench.commands._options import RUN_HELP, add_run, as_path

HELP = (
    "write tables.md, table CSVs and PNG plots of a benchmark run (or sweep.csv and the plots of "
    "a sweep folder) from its results files"
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_run(
        parser,
        f"the run or sweep folder to report ({RUN_HELP})",
        reads=True,
        positional_alias=True,
        dest="run_dir",
    )
    parser.add_argument(
        "--join",
        dest="with_runs",
        nargs="+",
        type=as_path,
        default=None,
        metavar="RUN",
        help="other runs of the same protocol and seeds whose further planners join the tables",
    )
    deprecated(parser, "--with", "--join", "with_runs", nargs="+", type=as_path)
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
        raise FileNotFoundError(f"{args.run_dir} is not a folder; give --run runs/<run>")
    if (args.run_dir / "sweep.json").is_file():  # a sweep folder (`hsqbench sweep --run`)
        if args.with_runs or args.reference:
            raise ValueError(
                f"{args.run_dir} is a sweep folder: --join and --reference are for benchmark runs"
            )
        report_sweep(args.run_dir)
        return 0
    for path in write_report(args.run_dir, tuple(args.with_runs or ()), args.reference):
        print(path)
    return 0


def report_sweep(root: Path) -> None:
    """sweep.csv, sweep.md and the plots of a sweep folder, from the runs in it."""
    from hsqbench.experiment.sweep import write_sweep_report

    written = write_sweep_report(root)
    plots = sum(p.suffix == ".png" for p in written)
    print(f"sweep report: {written[0]}, {written[1].name} and {plots} plots")
