#!/usr/bin/env bash
# Stage, on this machine, what bench/cuda_check/run.sh needs on a GPU machine that has python,
# a CUDA torch and nvcc but no network: the learned extra's pure-Python wheels (the versions
# this venv tested, no dependencies), the torch-cluster source (built there for its GPU),
# import stubs for cgn_pytorch's viewer (meshcat, IPython: imported at load, never called on
# our path; their real packages would not fit a 64 MiB transfer) and a few cached clouds.
#
#   bash bench/cuda_check/stage.sh [DEST=.devcheck] [N_CLOUDS=6]
#
# Needs `make learned` and the clouds of bench/eval_planner_ycb.py in $HSQ_CACHE_DIR. The GPU
# machine must have the rest: numpy, scipy, pyyaml, pytest, hypothesis, and torch-geometric's
# tqdm, jinja2, requests, scikit-learn and psutil.
set -euo pipefail
DEST=${1:-.devcheck}
N_CLOUDS=${2:-6}
PY=${PY:-.venv/bin/python}
TARGET_PY=${TARGET_PY:-3.12}  # the GPU machine's python (wheels here are py3-none-any)
CLOUDS="${HSQ_CACHE_DIR:?set HSQ_CACHE_DIR (source env.sh)}/eval_planner_ycb"
version() { "$PY" -c "import importlib.metadata as m; print(m.version('$1'))"; }

ls "$CLOUDS"/*.npz >/dev/null 2>&1 || {
    echo "no cached clouds in $CLOUDS: run python bench/eval_planner_ycb.py first" >&2
    exit 1
}
trap 'rm -rf "$DEST.partial"' EXIT  # nothing half-staged is left
rm -rf "$DEST.partial" && mkdir -p "$DEST.partial"/{wheels,src,stubs/meshcat,stubs/IPython,clouds}
"$PY" -m pip download --quiet --no-deps --only-binary=:all: --python-version "$TARGET_PY" \
    -d "$DEST.partial/wheels" "cgn-pytorch==$(version cgn-pytorch)" \
    "torch-geometric==$(version torch-geometric)" "trimesh==$(version trimesh)" \
    "importlib-resources==$(version importlib-resources)" \
    "pyparsing==$(version pyparsing)" \
    "setuptools==$(version setuptools)" "wheel==$(version wheel)"  # to build torch-cluster there
# ninja: torch builds the extension's files in parallel with it (one at a time without).
"$PY" -m pip download --quiet --no-deps --only-binary=:all: --python-version "$TARGET_PY" \
    --platform manylinux2014_x86_64 -d "$DEST.partial/wheels" ninja
"$PY" -m pip download --quiet --no-deps --no-build-isolation --no-binary=:all: \
    -d "$DEST.partial/src" "torch-cluster==$(version torch-cluster)"
for m in meshcat IPython; do
    cat >"$DEST.partial/stubs/$m/__init__.py" <<PYEOF
"""Stand-in for $m on the CUDA check machine: cgn_pytorch imports it, hsqbench never calls it."""


def __getattr__(name):
    if name.startswith("__"):
        raise AttributeError(name)

    def unavailable(*args, **kwargs):
        raise RuntimeError(f"$m.{name}: a stub on this machine (bench/cuda_check/stage.sh)")

    return unavailable
PYEOF
done
echo '"""Stub (bench/cuda_check/stage.sh)."""' >"$DEST.partial/stubs/meshcat/geometry.py"
# One resting pose (seed 0) of each of the first N objects by name; what the planner is given.
ls "$CLOUDS"/*_s0_*.npz | head -n "$N_CLOUDS" | "$PY" -c '
import sys, numpy as np, pathlib
for f in map(pathlib.Path, sys.stdin.read().split("\n")[:-1]):
    with np.load(f) as d:
        keep = {k: d[k] for k in ("points", "support_plane", "camera_positions")}
    np.savez_compressed(pathlib.Path(sys.argv[1]) / f.name, **keep)
' "$DEST.partial/clouds"
rm -rf "$DEST" && mv "$DEST.partial" "$DEST"
du -sh "$DEST"
