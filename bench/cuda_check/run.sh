#!/usr/bin/env bash
# The CUDA path of the contact-graspnet planner, on a GPU machine with python, a CUDA torch and
# nvcc but no network, from the folder bench/cuda_check/stage.sh filled: installs its wheels into
# DEV-site, builds torch-cluster there for this GPU (DEV-site is kept: a rerun after a timeout
# goes on from the build), runs the Contact-GraspNet tests (device "auto" is CUDA there) and
# bench/check_contact_graspnet_devices.py (CPU against CUDA: the same grasps? how fast?). Log
# and JSON go to $OUT (default DEV/out).
#
#   bash bench/cuda_check/run.sh [DEV=.devcheck]
#
# DEVICES="cpu cpu" rehearses it all on a machine without a GPU (torch-cluster built CPU-only).
set -uo pipefail
DEV=$(realpath "${1:-.devcheck}")
OUT=${OUT:-$DEV/out}
PY=${PY:-python3}
SITE=${SITE:-$DEV-site}
DEVICES=${DEVICES:-cpu cuda}
[[ " $DEVICES " == *" cuda "* ]] && GPU=cuda || GPU=cpu
mkdir -p "$OUT"
exec > >(tee "$OUT/cuda_check.log") 2>&1
step() { echo "== $* ($(date -u +%T))"; }

step machine
if [ "$GPU" = cuda ]; then
    nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader || exit 2
fi
"$PY" -c "import torch; print('torch', torch.__version__, 'cuda', torch.version.cuda)"
git log -1 --format='code %h %s' 2>/dev/null || true

step install
if [ ! -f "$SITE/.installed" ]; then
    rm -rf "$SITE"
    "$PY" -m pip install --quiet --no-deps --no-index --target "$SITE" "$DEV"/wheels/*.whl || exit 3
    touch "$SITE/.installed"
fi
export PYTHONPATH="$SITE" PATH="$SITE/bin:$PATH"
if [ "$GPU" = cuda ]; then
    ARCH=$("$PY" -c "import torch; print('%d.%d' % torch.cuda.get_device_capability())")
    export FORCE_CUDA=1 TORCH_CUDA_ARCH_LIST=$ARCH
else
    export FORCE_ONLY_CPU=1
fi
step "build torch-cluster for ${ARCH:+sm }${ARCH:-the cpu}"
if "$PY" -c "import torch_cluster" 2>/dev/null; then
    echo "already built in $SITE (a rerun)"
else
    MAX_JOBS=$(nproc) "$PY" -m pip install --quiet --no-deps --no-index --no-build-isolation \
        --target "$SITE" "$DEV"/src/torch_cluster-*.tar.gz || exit 4
fi
export PYTHONPATH="$PWD:$SITE:$DEV/stubs"
# The extra must import here: the tests would skip, not fail, without it.
"$PY" -c "from hsqbench.planner.learned import network; torch, fps, _ = network.import_backend(); \
x = torch.rand(4096, 3, device='$GPU'); \
print('learned extra imports; fps on $GPU:', fps(x, ratio=0.5).numel(), 'picks')" || exit 5

step tests
"$PY" -m pytest -q -p no:cacheprovider tests/test_contact_graspnet.py \
    tests/test_contact_graspnet_frames.py
tests=$?

step "cpu against cuda"
"$PY" bench/check_contact_graspnet_devices.py --clouds "$DEV/clouds" --limit 6 --seeds 0 1 \
    --devices $DEVICES --out "$OUT/cuda_check.json"
check=$?
step "done: tests rc $tests, comparison rc $check"
exit $((tests != 0 || check != 0))
