"""A user's runs never change a tracked file: named runs, default runs and sweeps go to a
git-ignored folder; only `make results` writes the tracked canonical runs under results/."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

from hsqbench.settings import REPO_ROOT, RESULTS_DIR

pytestmark = pytest.mark.skipif(
    shutil.which("git") is None or not (REPO_ROOT / ".git").exists(),
    reason="needs a git checkout of the repository",
)


def git_ignored(path: Path) -> bool:
    done = subprocess.run(
        ["git", "check-ignore", "-q", str(path)], cwd=REPO_ROOT, check=False, capture_output=True
    )
    assert done.returncode in (0, 1), done.stderr
    return done.returncode == 0


def test_benchmark_and_sweep_run_folders_are_git_ignored():
    from hsqbench.cli import build_parser
    from hsqbench.runs import run_folder

    named = run_folder("mine", "quick")
    dated = run_folder(None, "quick")
    sweep_default = build_parser().parse_args(["sweep", "depth_noise"]).run
    for folder in (named, dated, RESULTS_DIR / sweep_default):
        assert folder.is_relative_to(REPO_ROOT)
        for name in ("attempts.csv", "run.json", "tables.md", "gsr_per_object.png"):
            assert git_ignored(folder / name), folder / name


def test_canonical_results_stay_tracked():
    """The canonical runs under results/ (written by `make results`) are not ignored."""
    for name in ("attempts.csv", "run.json", "tables.md", "outcomes.png"):
        assert not git_ignored(REPO_ROOT / "results" / "paper3" / name)
    assert git_ignored(REPO_ROOT / "results" / "paper3" / ".lock")
