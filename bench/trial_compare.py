"""Two code versions' trials timed against each other (``bench_trial.py --compare REF``).

Each version runs in a worker process of its own (``bench_trial.py --worker`` with that
version's ``PYTHONPATH``), warmed up by one trial before any is timed; the parent hands both
workers the same presentations (a presentation: one isolated pose or one packed round, run for
every planner, as ``hsqbench benchmark`` runs them) one at a time, in ABBA order, so a change in
the machine's load falls on both alike. A worker runs a presentation through its own version's
``SerialExecutor`` and ``SimBackend`` and writes the rows with its own ``ResultStore``: the
path a benchmark takes, whatever either version does inside it. The outcome columns of every
attempt are compared too (a speed change that keeps outcomes must leave them identical).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tarfile
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

#: Attempt fields whose equality means the same outcome (timings and worker names aside).
OUTCOME_FIELDS = (
    "outcome",
    "target",
    "rank_executed",
    "n_grasps",
    "score",
    "width_m",
    "detail",
    "graspable",
    "object_pose",
)


def export_version(repo: Path, ref: str) -> tuple[Path, str]:
    """The tree of commit ``ref`` of ``repo``, unpacked (once) under the temp folder, and its
    full hash. ``git archive`` only reads the repository."""
    sha = subprocess.run(
        ["git", "-C", str(repo), "rev-parse", "--verify", f"{ref}^{{commit}}"],
        capture_output=True,
        text=True,
    )
    if sha.returncode:
        raise SystemExit(f"--compare {ref}: not a commit of {repo} ({sha.stderr.strip()})")
    commit = sha.stdout.strip()
    root = Path(tempfile.gettempdir()) / f"hsqbench-{commit[:12]}"
    if not (root / "hsqbench").is_dir():
        root.mkdir(parents=True, exist_ok=True)
        archive = subprocess.run(
            ["git", "-C", str(repo), "archive", "--format=tar", commit],
            capture_output=True,
            check=True,
        ).stdout
        with tempfile.TemporaryFile() as f:
            f.write(archive)
            f.seek(0)
            with tarfile.open(fileobj=f) as tar:
                tar.extractall(root, filter="data")
    return root, commit


@dataclass
class Worker:
    """A worker process running one code version (``bench_trial.py --worker``)."""

    label: str
    root: Path
    proc: subprocess.Popen

    @classmethod
    def start(cls, label: str, root: Path, script: Path, cache_dir: str) -> Worker:
        env = dict(os.environ, PYTHONPATH=str(root), HSQ_CACHE_DIR=cache_dir)
        for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
            env.setdefault(var, "1")
        proc = subprocess.Popen(
            [sys.executable, str(script), "--worker"],
            cwd=root,
            env=env,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
        )
        return cls(label, root, proc)

    def run(self, request: dict) -> dict:
        assert self.proc.stdin is not None and self.proc.stdout is not None
        self.proc.stdin.write(json.dumps(request) + "\n")
        self.proc.stdin.flush()
        line = self.proc.stdout.readline()
        if not line:
            raise SystemExit(f"the {self.label} worker ({self.root}) died; see its stderr above")
        return json.loads(line)

    def stop(self) -> None:
        if self.proc.stdin is not None:
            self.proc.stdin.close()
        self.proc.wait(timeout=60)


def compare(
    groups: list[dict], warmup: dict, ref_root: Path, new_root: Path, script: Path
) -> list[tuple[dict, dict, dict]]:
    """Run every group on both versions (ABBA order); ``(group, ref reply, new reply)``."""
    cache = os.environ.get("HSQ_CACHE_DIR") or str(new_root / "assets" / "build")
    ref = Worker.start("reference", ref_root, script, cache)
    new = Worker.start("new", new_root, script, cache)
    out = []
    try:
        for w in (ref, new):
            w.run(warmup)
        for i, group in enumerate(groups):
            first, second = (ref, new) if i % 2 == 0 else (new, ref)
            requests = version_requests(group)
            replies = {w.label: w.run(requests[w.label]) for w in (first, second)}
            out.append((group, replies["reference"], replies["new"]))
            r, n = replies["reference"], replies["new"]
            same = "same" if outcomes(r) == outcomes(n) else "DIFFERENT"
            print(
                f"{group['name']:34s} ref {r['wall_s']:6.2f} s ({r['cpu_s']:5.2f} cpu)  "
                f"new {n['wall_s']:6.2f} s ({n['cpu_s']:5.2f} cpu)  "
                f"new/ref {n['wall_s'] / r['wall_s']:.2f} ({n['cpu_s'] / r['cpu_s']:.2f} cpu)  "
                f"{same}",
                flush=True,
            )
    finally:
        ref.stop()
        new.stop()
    return out


def version_requests(group: dict) -> dict[str, dict]:
    """The request each version's worker gets for ``group``: ``--set`` overrides are the new
    tree's candidate setting, so the reference runs without them, at its own config."""
    return {"reference": {k: v for k, v in group.items() if k != "overrides"}, "new": group}


def outcomes(reply: dict) -> dict[str, list]:
    """Trial key -> the outcome fields of its attempts (or its error)."""
    return {t["key"]: t["outcomes"] if t["error"] is None else t["error"] for t in reply["trials"]}


def summarise(results: list[tuple[dict, dict, dict]]) -> list[str]:
    """Median per-trial wall and CPU seconds by kind (paper isolated, unseen isolated,
    packed), the ratios new/ref, and which trials changed outcome."""
    lines = []
    kinds = dict.fromkeys(g["kind"] for g, _, _ in results)
    for kind in kinds:
        rows = [(g, r, n) for g, r, n in results if g["kind"] == kind]
        per = {
            clock: [(r[clock] / len(g["specs"]), n[clock] / len(g["specs"])) for g, r, n in rows]
            for clock in ("wall_s", "cpu_s")
        }
        parts = []
        for clock, pairs in per.items():
            ref_med = float(np.median([p[0] for p in pairs]))
            new_med = float(np.median([p[1] for p in pairs]))
            paired = float(np.median([p[1] / p[0] for p in pairs]))
            parts.append(
                f"{clock[:-2]}: ref {ref_med:.2f} s, new {new_med:.2f} s, ratio of medians "
                f"{new_med / ref_med:.2f}, median paired ratio {paired:.2f}"
            )
        lines.append(f"{kind} ({len(rows)} presentations), per trial: " + "; ".join(parts))
    changed = []
    for _, r, n in results:
        a, b = outcomes(r), outcomes(n)
        changed += [k for k in a if a[k] != b.get(k)]
    lines.append(
        "outcomes: identical in every attempt"
        if not changed
        else f"outcomes DIFFER in {len(changed)} trial(s): {', '.join(changed)}"
    )
    return lines
