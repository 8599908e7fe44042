"""The rows of a run's CSV files (columns: :mod:`hsqbench.experiment.schema`): the rows of one finished trial
(:func:`rows_for`), every field on one line (:mod:`hsqbench.experiment.results` writes them)."""

from __future__ import annotations

import gzip
import json
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from hsqbench.experiment import schema
from hsqbench.experiment.backend import TrialRun
from hsqbench.experiment.config import ROUND_EXPERIMENTS
from hsqbench.experiment.csv_fields import format_row
from hsqbench.sim.outcome import Attempt, RoundResult
from hsqbench.sim.recorded_pose import pose7_in_frame

ATTEMPTS_FILE = "attempts.csv"
ROUNDS_FILE = "rounds.csv"
RUN_FILE = "run.json"
LOCK_FILE = ".lock"


# A packed file larger than this is stored as numbered pieces (``NAME.00``, ``NAME.01``, ...):
# consecutive bytes of one gzip stream, each under the 2 MiB a tracked file may take.
PACKED_PIECE_BYTES = 1_835_008  # 1.75 MiB


def attempts_paths(run_dir: Path) -> tuple[Path, Path]:
    """A run's attempts file, plain (appended to while the run goes) and packed (gzipped, as
    a canonical run keeps it: :func:`hsqbench.experiment.canonical.pack_attempts`)."""
    plain = run_dir / ATTEMPTS_FILE
    return plain, plain.with_name(plain.name + ".gz")


def packed_files(packed: Path) -> list[Path]:
    """The files that hold ``packed`` (a ``.gz`` path): itself, or its pieces in order; [] if
    neither is there."""
    if packed.exists():
        return [packed]
    return sorted(packed.parent.glob(f"{packed.name}.[0-9][0-9]"))


def read_packed(packed: Path) -> bytes:
    """The uncompressed bytes of ``packed``, whole or in pieces."""
    files = packed_files(packed)
    if not files:
        raise FileNotFoundError(f"{packed}: no such file, nor pieces {packed.name}.00, ...")
    return gzip.decompress(b"".join(f.read_bytes() for f in files))


def write_packed(packed: Path, data: bytes) -> list[Path]:
    """Write ``data`` gzipped to ``packed`` (level 9, mtime 0: the same bytes give the same
    files), in pieces when it is larger than :data:`PACKED_PIECE_BYTES`; replaces whatever held
    ``packed`` before and returns the files written."""
    blob = gzip.compress(data, compresslevel=9, mtime=0)
    if len(blob) <= PACKED_PIECE_BYTES:
        chunks = {packed: blob}
    else:
        starts = range(0, len(blob), PACKED_PIECE_BYTES)
        chunks = {
            packed.with_name(f"{packed.name}.{i:02d}"): blob[start : start + PACKED_PIECE_BYTES]
            for i, start in enumerate(starts)
        }
    for old in packed_files(packed):
        if old not in chunks:
            old.unlink()
    for path, chunk in chunks.items():
        tmp = path.with_name(path.name + ".tmp")
        tmp.write_bytes(chunk)
        tmp.replace(path)
    return list(chunks)


def has_attempts(run_dir: Path) -> bool:
    """Whether ``run_dir`` holds a run's attempts, plain or packed."""
    plain, packed = attempts_paths(run_dir)
    return plain.exists() or bool(packed_files(packed))


# The columns, their kinds and meanings: hsqbench.experiment.schema (the writer formats each
# field by its column's kind; readers type the columns from it).
ATTEMPT_COLUMNS = schema.ATTEMPT_COLUMNS
ROUND_COLUMNS = schema.ROUND_COLUMNS
FACTOR_NAMES = schema.FACTOR_NAMES

# Columns that depend on the machine or the moment, not on the trial: ignore them to compare runs.
VOLATILE_COLUMNS = (
    "perception_s",
    "planning_s",
    "execution_s",
    "motion_planning_s",
    "planner_stages_s",
    "trial_wall_s",
    "worker",
    "code_version",
    "finished_at",
)

STATUS_OK = "ok"
STATUS_ERROR = "error"


def _numbers(values: Any) -> str:
    """A sequence of floats as one field: space-separated, each exact (``repr``)."""
    return " ".join(repr(float(x)) for x in values)


def numbers(field: str) -> NDArray[np.float64]:
    """The floats of a field written by :func:`_numbers` (a pose column, ``top_scores``);
    empty for an empty field (older runs, or nothing recorded)."""
    return np.array([float(x) for x in field.split()], dtype=np.float64)


def pose_table(fields: Any) -> NDArray[np.float64]:
    """(N, 7) array of a pose column's fields (``x y z qw qx qy qz``), a row of NaN where a
    field is empty: ``pose_table(frame["grasp_pose"])``."""
    rows = [numbers(str(f)) if isinstance(f, str) else np.zeros(0) for f in fields]
    return np.array([r if r.size == 7 else np.full(7, np.nan) for r in rows]).reshape(-1, 7)


def _grasp_fields(a: Attempt) -> dict[str, Any]:
    """The grasp pose columns: world, and in the frame of the object at ``object_pose``."""
    if not a.grasp_pose:
        return {}
    in_object = pose7_in_frame(a.grasp_pose, a.object_pose) if a.object_pose else ()
    return {
        "grasp_pose": _numbers(a.grasp_pose),
        "grasp_flipped": a.grasp_flipped,
        "grasp_pose_object": _numbers(in_object),
    }


def _now() -> str:
    return datetime.now(UTC).isoformat(timespec="milliseconds")


def _attempt_records(run: TrialRun, common: dict[str, Any]) -> list[dict[str, Any]]:
    """One record per attempt of a finished trial, or the one error record of a failed one."""
    spec, result = run.spec, run.result
    attempts: list[dict[str, Any]] = []
    if result is None:
        attempts.append(
            {
                **common,
                "experiment": spec.experiment,
                "attempt_index": -1,
                "n_attempts": 0,
                "status": STATUS_ERROR,
                "detail": run.error or "unknown error",
            }
        )
    else:
        n = len(result.attempts)
        for i, a in enumerate(result.attempts):
            attempts.append(
                {
                    **common,
                    "experiment": spec.experiment,
                    "attempt_index": i,
                    "n_attempts": n,
                    "status": STATUS_OK,
                    "outcome": str(a.outcome),
                    "success": a.success,
                    "graspable": a.graspable,
                    "target": a.target,
                    "object_pose": _numbers(a.object_pose),
                    "resting_pose": a.resting_pose,
                    "rank_executed": a.rank_executed,
                    "n_grasps": a.n_grasps,
                    "score": float(a.score),
                    **{k: float(a.factors[k]) for k in FACTOR_NAMES if k in a.factors},
                    "factors": json.dumps(a.factors, sort_keys=True) if a.factors else "",
                    "width_m": float(a.width_m),
                    **_grasp_fields(a),
                    "top_scores": _numbers(a.top_scores),
                    "perception_s": float(a.perception_s),
                    "planning_s": float(a.planning_s),
                    "execution_s": float(a.execution_s),
                    "motion_planning_s": float(a.motion_planning_s),
                    "sim_time_s": float(a.sim_time_s),
                    "planner_stages_s": (
                        json.dumps(a.planner_stages_s, sort_keys=True) if a.planner_stages_s else ""
                    ),
                    "ranks_tried": a.ranks_tried,
                    "detail": a.detail,
                }
            )
    return attempts


def rows_for(
    run: TrialRun, config_hash: str, code_version: str, finished_at: str | None = None
) -> tuple[list[dict[str, str]], dict[str, str] | None]:
    """The attempt rows and (packed and pile only) the round row of one finished trial."""
    spec = run.spec
    finished_at = finished_at or _now()
    common = {
        "trial_key": spec.key,
        "planner": spec.planner,
        "base_seed": spec.base_seed,
        "trial_index": spec.index,
        "seed": spec.seed,
        "objects": ";".join(spec.objects),
        "trial_wall_s": run.wall_s,
        "worker": run.worker,
        "config_hash": config_hash,
        "code_version": code_version,
        "finished_at": finished_at,
        # The scene's settling (empty for an errored trial): the same on every row of a trial.
        "scene_settle_s": getattr(run.result, "scene_settle_s", None),
        "scene_max_speed": getattr(run.result, "scene_max_speed", None),
    }
    attempt_rows = [format_row(schema.ATTEMPTS, r) for r in _attempt_records(run, common)]
    if spec.experiment not in ROUND_EXPERIMENTS:
        return attempt_rows, None
    result = run.result
    if isinstance(result, RoundResult):
        round_row: dict[str, Any] = {
            **common,
            "n_objects": len(result.objects),
            "objects_cleared": ";".join(result.objects_cleared),
            "n_cleared": len(result.objects_cleared),
            "clearance_rate": result.clearance_rate,
            "objects_lost": ";".join(result.objects_lost),
            "n_lost": len(result.objects_lost),
            "objects_graspable": (
                None if result.objects_graspable is None else ";".join(result.objects_graspable)
            ),
            "n_graspable": (
                None if result.objects_graspable is None else len(result.objects_graspable)
            ),
            "n_attempts": len(result.attempts),
            "n_success": sum(a.success for a in result.attempts),
            "status": STATUS_OK,
            "detail": "; ".join(
                filter(None, (spec.draw_note, _unplaced_note(result.objects_unplaced)))
            ),
        }
    else:
        round_row = {
            **common,
            "n_objects": len(spec.objects),
            "n_attempts": 0,
            "status": STATUS_ERROR,
            "detail": "; ".join(filter(None, (run.error or "unknown error", spec.draw_note))),
        }
    return attempt_rows, format_row(schema.ROUNDS, round_row)


def _unplaced_note(names: list[str]) -> str:
    """The round detail's note on drawn objects its scene did not place (not presented)."""
    return f"not placed (not presented): {';'.join(names)}" if names else ""
