"""The results of a run: append-only CSV files that survive a killed run.

Layout of ``runs/<run>/``:

- ``attempts.csv``: one row per grasp attempt (isolated, packed and pile), or one
  ``status=error`` row for a trial that could not run (``attempt_index=-1``, ``n_attempts=0``).
- ``rounds.csv``: one row per packed or pile round (``trial_key`` names which), written *after*
  the round's attempt rows; its
  ``detail`` names the draws rejected before the round's objects, if any (not placeable).
- ``run.json``: the full config, its hash, code version, machine (host, CPU model, cores, Python
  and the versions of every package hsqbench depends on: :mod:`hsqbench.experiment.machine`), the
  sessions that ran (each with its own machine record: a resume may run elsewhere) and
  ``packed_draws`` and ``pile_draws`` (each round's objects and rejected draws).

Durability: only the parent process writes. All rows of one trial go to a file in one
``os.write`` on an ``O_APPEND`` descriptor, followed by ``fsync``; every field is kept on one
line. A trial is *complete* when all its attempt rows (indexes ``0..n_attempts-1``, or the error
row) are present and, for a packed round, its round row too. When a run is resumed, a trailing
partial line (the process was killed mid-write) and the rows of incomplete trials are removed by
rewriting the files atomically (temporary file + ``os.replace``); complete trials are skipped, so
none is lost and none is counted twice. Readers (the report) also deduplicate by trial key.
"""

from __future__ import annotations

import contextlib
import csv
import io
import json
import os
import warnings
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from hsqbench.experiment.backend import TrialRun
from hsqbench.experiment.config import ROUND_EXPERIMENTS
from hsqbench.experiment.rows import (
    ATTEMPT_COLUMNS,
    ATTEMPTS_FILE,
    FACTOR_NAMES,
    LOCK_FILE,
    ROUND_COLUMNS,
    ROUNDS_FILE,
    RUN_FILE,
    STATUS_ERROR,
    STATUS_OK,
    VOLATILE_COLUMNS,
    packed_files,
    read_packed,
    rows_for,
)

__all__ = [
    "ATTEMPTS_FILE",
    "ATTEMPT_COLUMNS",
    "FACTOR_NAMES",
    "LOCK_FILE",
    "ROUNDS_FILE",
    "ROUND_COLUMNS",
    "RUN_FILE",
    "STATUS_ERROR",
    "STATUS_OK",
    "VOLATILE_COLUMNS",
    "ResultStore",
    "ResultsError",
    "RunResults",
    "check_consistent",
    "collect",
    "load_results",
    "read_rows",
    "rows_for",
]


class ResultsError(RuntimeError):
    """A results folder cannot be used as asked (wrong config, damaged file, in use)."""


def _encode(rows: Iterable[dict[str, str]], columns: tuple[str, ...]) -> bytes:
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=columns, lineterminator="\n")
    writer.writerows(rows)
    return buf.getvalue().encode()


def _header(columns: tuple[str, ...]) -> bytes:
    return (",".join(columns) + "\n").encode()


def _append(path: Path, data: bytes) -> None:
    """One write (looped only if the kernel writes short) + fsync, on an O_APPEND descriptor."""
    fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
    try:
        view = memoryview(data)
        while view:
            view = view[os.write(fd, view) :]
        os.fsync(fd)
    finally:
        os.close(fd)


def _replace(path: Path, data: bytes) -> None:
    """Atomically replace ``path`` by ``data`` (write a sibling, fsync, rename)."""
    tmp = path.with_name(f".{path.name}.tmp")
    with open(tmp, "wb") as f:
        f.write(data)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)


@dataclass
class ParsedFile:
    """The rows of one results file, and what was wrong with its tail."""

    rows: list[dict[str, str]] = field(default_factory=list)
    partial_tail: bool = False


def read_rows(path: Path, columns: tuple[str, ...], allow_older: bool = False) -> ParsedFile:
    """Parse a results CSV, dropping a trailing partial line (a write cut by a kill).

    ``path`` or, when it is absent, ``path`` + ``.gz`` (whole or in pieces) is read.
    ``allow_older``: a file written by an earlier version, whose columns are a subset of
    ``columns``, is read with the missing columns empty (for reports; never for appending).

    Raises:
        ResultsError: the header differs from ``columns`` or a complete line is malformed.
    """
    packed = path.with_name(path.name + ".gz")
    if not path.exists() and not packed_files(packed):
        return ParsedFile()
    # A committed run may hold its CSV gzipped (large runs); it is read, never appended to.
    data = path.read_bytes() if path.exists() else read_packed(packed)
    partial = bool(data) and not data.endswith(b"\n")
    if partial:
        data = data[: data.rfind(b"\n") + 1]
    lines = data.decode("utf-8", errors="replace").splitlines()
    if not lines:
        return ParsedFile([], partial)
    header = next(csv.reader([lines[0]]))
    older = allow_older and set(header) < set(columns)
    if tuple(header) != columns and not older:
        raise ResultsError(
            f"{path}: its columns differ from this version's ({len(header)} vs {len(columns)} "
            "columns); it was written by another version of hsqbench: use a new --run name"
        )
    rows = []
    blank = dict.fromkeys(columns, "")
    for lineno, fields in enumerate(csv.reader(lines[1:]), start=2):
        if len(fields) != len(header):
            raise ResultsError(
                f"{path}:{lineno}: malformed row ({len(fields)} fields, expected {len(header)}); "
                "the file was edited or written by two processes at once"
            )
        rows.append({**blank, **dict(zip(header, fields, strict=True))})
    return ParsedFile(rows, partial)


@dataclass
class RunResults:
    """The complete trials of a run (deduplicated), as string rows."""

    attempts: list[dict[str, str]]
    rounds: list[dict[str, str]]
    complete_keys: set[str]
    error_keys: set[str]
    incomplete_keys: set[str]
    duplicate_keys: set[str]
    partial_tail: bool


def collect(attempt_rows: list[dict[str, str]], round_rows: list[dict[str, str]]) -> RunResults:
    """Keep complete trials only, each once (the first complete copy of a key wins)."""
    by_key: dict[str, list[dict[str, str]]] = {}
    for row in attempt_rows:
        by_key.setdefault(row["trial_key"], []).append(row)
    rounds_by_key: dict[str, list[dict[str, str]]] = {}
    for row in round_rows:
        rounds_by_key.setdefault(row["trial_key"], []).append(row)

    attempts: list[dict[str, str]] = []
    rounds: list[dict[str, str]] = []
    complete: set[str] = set()
    errors: set[str] = set()
    incomplete: set[str] = set()
    duplicates: set[str] = set()
    for key, rows in by_key.items():
        chosen = _complete_copy(rows)
        if chosen is None:
            incomplete.add(key)
            continue
        if len(rows) > len(chosen):
            duplicates.add(key)
        if rows[0]["experiment"] in ROUND_EXPERIMENTS:
            candidates = rounds_by_key.get(key, [])
            if not candidates:
                incomplete.add(key)
                continue
            if len(candidates) > 1:
                duplicates.add(key)
            rounds.append(candidates[0])
        complete.add(key)
        if chosen[0]["status"] == STATUS_ERROR:
            errors.add(key)
        attempts.extend(chosen)
    orphans = set(rounds_by_key) - set(by_key)
    incomplete |= orphans
    return RunResults(attempts, rounds, complete, errors, incomplete, duplicates, False)


def _complete_copy(rows: list[dict[str, str]]) -> list[dict[str, str]] | None:
    """The first full record of one trial (its error row, or all its attempt rows), if any."""
    for row in rows:
        if row["status"] == STATUS_ERROR:
            return [row]
        n = int(row["n_attempts"])
        same: dict[int, dict[str, str]] = {}
        for r in rows:
            if r["status"] == STATUS_OK and r["n_attempts"] == row["n_attempts"]:
                same.setdefault(int(r["attempt_index"]), r)
        if n >= 1 and all(i in same for i in range(n)):
            return [same[i] for i in range(n)]
    return None


def load_results(run_dir: str | Path) -> RunResults:
    """Read a run's results files (read only), keeping complete trials once each; files of an
    earlier version (fewer columns) are read with the new columns empty."""
    run_dir = Path(run_dir)
    att = read_rows(run_dir / ATTEMPTS_FILE, ATTEMPT_COLUMNS, allow_older=True)
    rnd = read_rows(run_dir / ROUNDS_FILE, ROUND_COLUMNS, allow_older=True)
    results = collect(att.rows, rnd.rows)
    results.partial_tail = att.partial_tail or rnd.partial_tail
    return results


class ResultStore:
    """The parent process's writer for one run folder (see the module docstring)."""

    def __init__(self, run_dir: str | Path) -> None:
        self.run_dir = Path(run_dir)
        self.attempts_path = self.run_dir / ATTEMPTS_FILE
        self.rounds_path = self.run_dir / ROUNDS_FILE
        self._done: set[str] = set()
        self._lock_fd: int | None = None

    # -- metadata -------------------------------------------------------------------------
    def read_meta(self) -> dict[str, Any] | None:
        path = self.run_dir / RUN_FILE
        if not path.exists():
            return None
        try:
            return json.loads(path.read_text())
        except json.JSONDecodeError as exc:
            raise ResultsError(f"{path}: not valid JSON ({exc})") from exc

    def write_meta(self, meta: dict[str, Any]) -> None:
        _replace(self.run_dir / RUN_FILE, (json.dumps(meta, indent=2) + "\n").encode())

    # -- lifecycle ------------------------------------------------------------------------
    @contextlib.contextmanager
    def locked(self) -> Iterator[ResultStore]:
        """Hold an exclusive lock on the run folder, so two runs never append to one file."""
        self.run_dir.mkdir(parents=True, exist_ok=True)
        fd = os.open(self.run_dir / LOCK_FILE, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            import fcntl

            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except ImportError:  # not POSIX: no lock, documented limitation
            pass
        except BlockingIOError as exc:
            os.close(fd)
            raise ResultsError(
                f"{self.run_dir} is being written by another hsqbench process; wait for it or "
                "choose another --run name"
            ) from exc
        self._lock_fd = fd
        try:
            yield self
        finally:
            os.close(fd)
            self._lock_fd = None

    def prepare(self, retry_errors: bool = False) -> RunResults:
        """Create the files, or repair them for a resume: drop a partial tail, incomplete trials
        and (with ``retry_errors``) error trials. Returns what is kept."""
        self.run_dir.mkdir(parents=True, exist_ok=True)
        att = read_rows(self.attempts_path, ATTEMPT_COLUMNS)
        rnd = read_rows(self.rounds_path, ROUND_COLUMNS)
        results = collect(att.rows, rnd.rows)
        results.partial_tail = att.partial_tail or rnd.partial_tail
        drop = set(results.incomplete_keys)
        if retry_errors:
            drop |= results.error_keys
        dirty = bool(drop) or bool(results.duplicate_keys) or results.partial_tail
        if dirty or not self.attempts_path.exists():
            if drop:
                results = collect(
                    [r for r in results.attempts if r["trial_key"] not in drop],
                    [r for r in results.rounds if r["trial_key"] not in drop],
                )
            _replace(
                self.attempts_path,
                _header(ATTEMPT_COLUMNS) + _encode(results.attempts, ATTEMPT_COLUMNS),
            )
            _replace(
                self.rounds_path, _header(ROUND_COLUMNS) + _encode(results.rounds, ROUND_COLUMNS)
            )
        elif not self.rounds_path.exists():
            _replace(self.rounds_path, _header(ROUND_COLUMNS))
        self._done = set(results.complete_keys)
        return results

    def append(self, run: TrialRun, config_hash: str, code_version: str) -> list[dict[str, str]]:
        """Record one finished trial durably; returns its attempt rows.

        Raises:
            ResultsError: the trial is already recorded (it would be counted twice).
        """
        key = run.spec.key
        if key in self._done:
            raise ResultsError(f"trial {key} is already recorded; refusing to count it twice")
        attempt_rows, round_row = rows_for(run, config_hash, code_version)
        _append(self.attempts_path, _encode(attempt_rows, ATTEMPT_COLUMNS))
        if round_row is not None:
            _append(self.rounds_path, _encode([round_row], ROUND_COLUMNS))
        self._done.add(key)
        return attempt_rows

    @property
    def done_keys(self) -> set[str]:
        return set(self._done)


def check_consistent(results: RunResults) -> None:
    """Warn about anything a reader had to repair."""
    if results.duplicate_keys:
        warnings.warn(
            f"{len(results.duplicate_keys)} trial(s) were recorded more than once; each is "
            "counted once",
            stacklevel=2,
        )
    if results.incomplete_keys:
        warnings.warn(
            f"{len(results.incomplete_keys)} incomplete trial(s) (a run was stopped mid-trial) "
            "are left out; resume the run to finish them",
            stacklevel=2,
        )
