"""What a run was computed on, for ``run.json``: CPU, cores, Python and the package versions.

Physics (mujoco), linear algebra (numpy, scipy), convex decomposition (coacd) and mesh handling
(trimesh) all change numbers between releases, so a rerun can only be expected to match when
these match. The package list is hsqbench's own declared dependencies (one source of truth:
``pyproject.toml``) plus optional ones that can run trials (ray).
"""

from __future__ import annotations

import os
import platform
import re
import socket
import sys
from importlib import metadata
from pathlib import Path
from typing import Any

OPTIONAL_PACKAGES = ("ray",)


def cpu_model() -> str:
    """The CPU's marketing name (``/proc/cpuinfo`` on Linux, sysctl on macOS), else the
    architecture."""
    cpuinfo = Path("/proc/cpuinfo")
    if cpuinfo.is_file():
        for line in cpuinfo.read_text(errors="replace").splitlines():
            key, _, value = line.partition(":")
            if key.strip() in ("model name", "Hardware", "Processor") and value.strip():
                return value.strip()
    if sys.platform == "darwin":
        import subprocess

        try:
            out = subprocess.run(
                ["sysctl", "-n", "machdep.cpu.brand_string"],
                capture_output=True,
                text=True,
                timeout=5,
                check=True,
            )
            if out.stdout.strip():
                return out.stdout.strip()
        except (OSError, subprocess.SubprocessError):
            pass
    return platform.processor() or platform.machine() or "unknown"


def usable_cores() -> int:
    """Cores this process may run on (CPU affinity, e.g. a container's limit)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


def _requirement_name(requirement: str) -> str:
    return re.split(r"[\s;<>=!~\[(]", requirement.strip(), maxsplit=1)[0]


def package_versions() -> dict[str, str]:
    """Installed version of each runtime dependency of hsqbench (and of ray when installed);
    ``"missing"`` for a declared dependency that is not installed."""
    try:
        requires = metadata.requires("hsqbench") or []
    except metadata.PackageNotFoundError:  # running from a tree that was never installed
        requires = []
    names = [_requirement_name(r) for r in requires if "extra ==" not in r]
    versions: dict[str, str] = {}
    for name in names:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            versions[name] = "missing"
    for name in OPTIONAL_PACKAGES:
        try:
            versions[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            continue
    return dict(sorted(versions.items()))


def machine_info() -> dict[str, Any]:
    """The machine and software of this process, as recorded in ``run.json``."""
    return {
        "host": socket.gethostname(),
        "platform": platform.platform(),
        "cpu_model": cpu_model(),
        "cpus": os.cpu_count(),
        "usable_cores": usable_cores(),
        "python": sys.version.split()[0],
        "packages": package_versions(),
    }
