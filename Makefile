# hsqbench: `make benchmark` runs the paper's experiments, `make test` checks the code.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
LEARNED_STAMP := $(VENV)/.learned
# `make test` (and CI) installs the learned extra too, so the real network is tested on every
# submission; LEARNED=0 leaves it out (its tests then skip, saying why).
LEARNED ?= 1
JOBS ?= $(shell nproc 2>/dev/null || echo 2)

export MUJOCO_GL ?= egl
export PYOPENGL_PLATFORM ?= egl

.PHONY: help install learned test test-slow lint format bench benchmark sweeps assets clean

help:
	@echo "make benchmark   run both experiments of the paper and write results/<run>/ (CONFIG=quick ...)"
	@echo "make test        run the test suite (fast checks, as CI does)"
	@echo "make test-slow   run the slow checks too (every object of the library, long fits)"
	@echo "make sweeps      robustness sweeps: depth noise, calibration, one camera, pad friction (results/sweeps/)"
	@echo "make bench       time the planner and the trial loop (bench/)"
	@echo "make assets      build the whole object library (optional: benchmark builds what it needs)"
	@echo "make learned     install the contact-graspnet planner (torch, cgn-pytorch, torch-cluster)"
	@echo "make lint        ruff"

# The venv is (re)built when it is missing or when pyproject.toml changed since the last install.
# Extras: dev (tests, lint) and ray (the Ray executor, so its equivalence test runs, as in CI;
# about 80 MB); EXTRAS=dev installs without Ray.
EXTRAS ?= dev,ray
$(STAMP): pyproject.toml
	@test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[$(EXTRAS)]"
	@touch $(STAMP)

install: $(STAMP)

# torch for the learned extra: without an NVIDIA driver the CPU-only build (190 MB, not ~3 GB of
# CUDA libraries), from PyTorch's CPU index or a local wheel; with one, the default wheel. Only
# torch itself comes from that index (--no-deps); its dependencies come with the extra, from PyPI.
ifeq ($(shell command -v nvidia-smi 2>/dev/null),)
TORCH_PIP ?= "torch==2.13.0+cpu" --extra-index-url https://download.pytorch.org/whl/cpu
else
TORCH_PIP ?= "torch>=2.5"
endif
# torch-cluster compiles one file at a time (MAX_JOBS=1: a shared machine; ~11 min on 2 cores
# the first time). pip caches the wheel it builds, so later venvs install it in seconds.
$(LEARNED_STAMP): $(STAMP)
	$(PY) -c "import torch" 2>/dev/null || $(PY) -m pip install --quiet --retries 1 --no-deps $(TORCH_PIP)
	$(PY) -m pip install --quiet wheel -e ".[learned]"
	$(PY) -m pip install --quiet --no-deps "cgn-pytorch==0.4.3"
	MAX_JOBS=$${MAX_JOBS:-1} $(PY) -m pip install --quiet --no-build-isolation "torch-cluster==1.6.3"
	$(PY) -c "import cgn_pytorch, torch_cluster; print('contact-graspnet: installed')"
	@touch $(LEARNED_STAMP)

learned: $(LEARNED_STAMP)

test: $(STAMP) $(if $(filter 1,$(LEARNED)),$(LEARNED_STAMP))
	$(PY) -m pytest -q -m "not slow"

test-slow: $(STAMP) $(if $(filter 1,$(LEARNED)),$(LEARNED_STAMP))
	$(PY) -m pytest -q

lint: $(STAMP)
	$(VENV)/bin/ruff check hsqbench tests bench
	$(VENV)/bin/ruff format --check hsqbench tests bench

format: $(STAMP)
	$(VENV)/bin/ruff format hsqbench tests bench
	$(VENV)/bin/ruff check --fix hsqbench tests bench

bench: $(STAMP)
	@for f in bench/bench_*.py; do echo "== $$f"; $(PY) $$f || exit 1; done

# Build every object of the library once (CoACD hulls, inertia, MuJoCo meshes; cached in
# HSQ_CACHE_DIR). Not needed before a benchmark, which builds exactly the objects it uses.
assets: $(STAMP)
	$(PY) -m hsqbench.cli assets build --all --jobs $(JOBS)

# A protocol's experiments (default: the paper's two) with all its planners. The command builds
# the objects the protocol uses (and downloads missing YCB ones) before the first trial.
# Re-running continues the same run (--resume): finished trials are kept, so a killed benchmark
# loses nothing. RUN=name starts another run; CONFIG=quick (or a YAML path) another protocol.
CONFIG ?= paper
RUN ?= $(CONFIG)
benchmark: $(STAMP)
	$(PY) -m hsqbench.cli benchmark --config $(CONFIG) --run $(RUN) --jobs $(JOBS) --resume
	@rm -rf results/latest && cp -r results/$(RUN) results/latest && rm -f results/latest/.lock
	@echo "tables: results/latest/tables.md (copied from results/$(RUN))"

# The built-in robustness sweeps (configs/protocols/sweeps/) on the isolated protocol, paper and unseen
# objects, into results/sweeps/ (sweep.csv, one PNG per parameter, a run per point). With JOBS=2
# on a 2-core machine the unseen objects' three seeds took 49 min for hsq and antipodal alone;
# contact-graspnet, where installed, adds about 15 min per sweep on the paper's objects
# (SWEEP_PLANNERS="hsq single-sq antipodal" leaves it out; a later run adds it to the same runs).
# Rerunning resumes; SWEEP_ARGS="--seeds 0 1 2 3 4" scales them up (new runs, narrower bands).
SWEEPS ?= depth_noise calibration cameras pad_friction
SWEEP_PLANNERS ?=
SWEEP_ARGS ?=
sweeps: $(STAMP)
	$(PY) -m hsqbench.cli sweep $(SWEEPS) --run sweeps --jobs $(JOBS) \
		$(if $(SWEEP_PLANNERS),--planners $(SWEEP_PLANNERS)) $(SWEEP_ARGS)

clean:
	rm -rf $(VENV) build *.egg-info .pytest_cache .ruff_cache
