"""One schema for the results files: the writer formats by it, ``load_run`` types by it (under the
pandas CI installs and the oldest the package allows), docs/results-format.md is rendered from it."""

from __future__ import annotations

import csv
import io
import json
import os
import re
import subprocess
import sys
import tomllib
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from hsqbench.experiment import csv_fields, schema, schema_doc
from hsqbench.experiment.config import ExperimentConfig, IsolatedConfig, PackedConfig
from hsqbench.experiment.executor import SerialExecutor
from hsqbench.experiment.run_data import load_run
from hsqbench.experiment.runner import run_benchmark
from tests.fake_backend import FakeBackend

REPO = Path(__file__).resolve().parents[1]
CONFIG = ExperimentConfig(
    planners=("a", "b"),
    isolated=IsolatedConfig(objects=("mug", "bowl", "apple"), attempts_per_object=2),
    packed=PackedConfig(objects=("mug", "bowl", "apple", "banana"), rounds=2, objects_per_round=3),
)


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory) -> Path:
    """A run with ok rows, error rows (apple raises) and packed rounds."""
    run = tmp_path_factory.mktemp("schema") / "run"
    backend = FakeBackend(raise_on=("apple",))
    run_benchmark(CONFIG, run, backend=backend, executor=SerialExecutor(), progress=False)
    return run


def _is_text(dtype) -> bool:
    # pandas 3: the str dtype; pandas 2: object
    return dtype == np.dtype(object) or isinstance(dtype, pd.StringDtype)


def check_dtypes(frame: pd.DataFrame, columns: tuple[schema.Column, ...]) -> None:
    assert list(frame.columns) == [c.name for c in columns]
    for c in columns:
        dtype = frame[c.name].dtype
        if c.kind == "text":
            assert _is_text(dtype), (c.name, dtype)
        else:
            assert dtype == np.dtype(c.dtype), (c.name, dtype)


def test_load_run_types_every_column_by_the_schema(run_dir) -> None:
    data = load_run(run_dir)
    check_dtypes(data.attempts, schema.ATTEMPTS)
    check_dtypes(data.rounds, schema.ROUNDS)
    a = data.attempts
    assert (a["status"] == "error").any() and (a["status"] == "ok").any()
    # What the issue found raising under pandas 3.1: means of number columns per planner.
    widths = a.groupby("planner")["width_m"].mean()
    assert set(widths.index) == {"a", "b"} and widths.between(0.01, 0.08).all()
    ok = a[a["status"] == "ok"]
    assert (ok["score"] > 0).all() and (ok["n_grasps"] >= 0).all()
    assert set(ok["success"]) <= {0.0, 1.0}
    errors = a[a["status"] == "error"]
    # An error row's missing numbers are NaN, its missing text is empty.
    assert errors["success"].isna().all() and (errors["outcome"] == "").all()
    assert (errors["attempt_index"] == -1).all()
    assert data.rounds["n_objects"].sum() == 2 * 2 * 3  # planners x rounds x objects


def test_a_damaged_number_field_is_named(run_dir, tmp_path) -> None:
    copy = tmp_path / "run"
    copy.mkdir()
    for f in run_dir.iterdir():
        if f.is_file():
            (copy / f.name).write_bytes(f.read_bytes())
    text = (copy / "attempts.csv").read_text().splitlines()
    header = text[0].split(",")
    # Replace the first ok row's width by text (as a hand edit might).
    i = next(i for i, line in enumerate(text) if ",ok," in line)
    fields = next(csv.reader([text[i]]))
    fields[header.index("width_m")] = "wide"
    buf = io.StringIO()
    csv.writer(buf, lineterminator="").writerow(fields)
    text[i] = buf.getvalue()
    (copy / "attempts.csv").write_text("\n".join(text) + "\n")
    with pytest.raises(schema.SchemaError, match=r"width_m is 'wide', not a float"):
        load_run(copy)


def test_the_writer_formats_by_the_column_kind() -> None:
    width = schema.column("attempts", "width_m")
    success = schema.column("attempts", "success")
    rank = schema.column("attempts", "rank_executed")
    detail = schema.column("attempts", "detail")
    # NumPy scalars are written as the numbers they hold (repr(np.float64) is "np.float64(..)").
    assert csv_fields.format_field(width, np.float64(0.035)) == "0.035"
    assert csv_fields.format_field(width, np.float32(0.5)) == "0.5"
    assert csv_fields.format_field(width, float("nan")) == ""
    assert csv_fields.format_field(success, np.bool_(True)) == "1"
    assert csv_fields.format_field(success, False) == "0"
    assert csv_fields.format_field(rank, np.int64(3)) == "3"
    assert csv_fields.format_field(detail, "a\nb") == "a | b"
    for col, bad in ((width, "0.03"), (rank, 2.5), (success, 2)):
        with pytest.raises(schema.SchemaError, match=col.name):
            csv_fields.format_field(col, bad)
    # Written and read back, a value is the value computed.
    identity = dict.fromkeys(("base_seed", "trial_index", "attempt_index", "n_attempts"), 0)
    row = csv_fields.format_row(schema.ATTEMPTS, {"width_m": 0.1 + 0.2, "seed": 7, **identity})
    back = csv_fields.typed_frame([row], "attempts")
    assert back.at[0, "width_m"] == 0.1 + 0.2 and back.at[0, "seed"] == 7


def test_the_doc_tables_are_the_schema() -> None:
    text = schema_doc.DOC.read_text()
    assert schema_doc.update_doc(text) == text, (
        "docs/results-format.md's column tables differ from hsqbench/experiment/schema.py: run "
        "`python -m hsqbench.experiment.schema_doc`"
    )
    first_cells = re.findall(r"^\| (`.*?) \|", text, flags=re.MULTILINE)
    documented = {n for cell in first_cells for n in re.findall(r"`(\w+)`", cell)}
    assert set(schema.ATTEMPT_COLUMNS) <= documented


def test_every_outcome_is_documented() -> None:
    from hsqbench.sim.outcome import Outcome

    meaning = schema.column("attempts", "outcome").meaning
    assert all(f"`{o}`" in meaning for o in Outcome)


def _oldest_pandas() -> str:
    deps = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]["dependencies"]
    spec = next(d for d in deps if re.match(r"pandas\b", d))
    return re.fullmatch(r"pandas>=([\d.]+)", spec.split(";")[0].strip())[1]


_OLD_PANDAS_CHECK = """
import json, sys
import pandas as pd
from tests.test_experiment_schema import check_dtypes, report_tables
from hsqbench.experiment import schema
from hsqbench.experiment.run_data import load_run
data = load_run(sys.argv[1])
check_dtypes(data.attempts, schema.ATTEMPTS)
check_dtypes(data.rounds, schema.ROUNDS)
print(json.dumps({"pandas": pd.__version__, "tables": report_tables(sys.argv[1])}))
"""


def report_tables(run_dir: str | Path) -> dict[str, str]:
    """The report's tables of a run (tables.md and the CSVs; no plots, to stay quick)."""
    from hsqbench.experiment import report

    out = Path(run_dir).parent / f"report-{os.getpid()}"
    out.mkdir()
    for f in Path(run_dir).iterdir():
        if f.is_file():
            (out / f.name).write_bytes(f.read_bytes())
    plots, report.write_plots = report.write_plots, lambda *a, **k: []
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the run's error rows are meant
            written = report.write_report(out)
    finally:
        report.write_plots = plots
    return {p.name: p.read_text() for p in written}


def _overlay(version: str) -> Path:
    """pandas ``version`` installed (pip --target) beside this environment's packages, in the
    user's cache: put first on PYTHONPATH, it is the pandas imported."""
    tag = f"pandas-{version}-py{sys.version_info.major}{sys.version_info.minor}"
    cache = Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "hsqbench" / tag
    if (cache / ".complete").exists():
        return cache
    # pandas 2 needs pytz and tzdata, which pandas 3 (this environment's) does not.
    cmd = [sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--only-binary=:all:"]
    cmd += ["--upgrade", "--target", str(cache), f"pandas=={version}", "pytz", "tzdata"]
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    if done.returncode != 0:
        if os.environ.get("CI"):
            pytest.fail(f"could not install pandas {version}: {done.stderr[-2000:]}")
        pytest.skip(f"pandas {version} could not be installed (offline?): {done.stderr[-300:]}")
    (cache / ".complete").touch()
    return cache


def test_the_oldest_pandas_allowed_types_and_reports_a_run_alike(run_dir) -> None:
    """pyproject's lower bound of pandas gives the same dtypes and the same report tables."""
    version = _oldest_pandas()
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(_overlay(version)), str(REPO)])}
    done = subprocess.run(
        [sys.executable, "-c", _OLD_PANDAS_CHECK, str(run_dir)],
        capture_output=True,
        text=True,
        env=env,
        cwd=REPO,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr[-4000:]
    old = json.loads(done.stdout.strip().splitlines()[-1])
    assert old["pandas"] == version != pd.__version__
    here = report_tables(run_dir)
    assert "tables.md" in here and old["tables"] == here


#: The columns of attempts.csv in hsqbench's first version (git history of results.py).
FIRST_ATTEMPT_COLUMNS = (
    *("trial_key", "experiment", "planner", "base_seed", "trial_index", "seed", "objects"),
    *("attempt_index", "n_attempts", "status", "outcome", "success", "target", "rank_executed"),
    *("n_grasps", "score", *schema.FACTOR_NAMES, "factors", "width_m", "perception_s"),
    *("planning_s", "execution_s", "detail", "trial_wall_s", "worker", "config_hash"),
    *("code_version", "finished_at"),
)


def test_a_run_of_an_older_version_loads_with_the_same_dtypes(run_dir, tmp_path) -> None:
    """Its missing columns are NaN (numbers) or empty (text), typed as the schema says."""
    old = tmp_path / "old"
    old.mkdir()
    for f in run_dir.iterdir():
        if f.is_file() and f.name != "attempts.csv":
            (old / f.name).write_bytes(f.read_bytes())
    with (run_dir / "attempts.csv").open() as src, (old / "attempts.csv").open("w") as dst:
        writer = csv.DictWriter(dst, FIRST_ATTEMPT_COLUMNS, extrasaction="ignore")
        writer.writeheader()
        writer.writerows(csv.DictReader(src))
    data = load_run(old)
    check_dtypes(data.attempts, schema.ATTEMPTS)
    a = data.attempts
    assert a["sim_time_s"].isna().all() and (a["grasp_pose"] == "").all()
    assert a["width_m"].equals(load_run(run_dir).attempts["width_m"])
