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

.PHONY: help install learned test test-slow lint format bench benchmark sweeps results assets clean

help:
	@echo "make benchmark   run both experiments of the paper into runs/<run>/ (PROTOCOL=quick ...)"
	@echo "make test        run the test suite (fast checks, as CI does)"
	@echo "make test-slow   run the slow checks too (every object of the library, long fits)"
	@echo "make sweeps      robustness sweeps: depth noise, calibration, one camera, pad friction (runs/sweeps/)"
	@echo "make results     regenerate the canonical runs behind the README into results/ (~6 h on 2 cores, resumable)"
	@echo "make bench       time the planner and the trial loop (bench/)"
	@echo "make assets      build the whole object library (optional: benchmark builds what it needs)"
	@echo "make learned     install the contact-graspnet planner (torch, torch-geometric, cgn-pytorch; wheels only)"
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
# Everything installs from wheels: the network's farthest point sampling, radius and k-nearest
# searches, which torch-geometric takes from the torch-cluster package (no wheel on PyPI; 11 to 30
# minutes to compile on 2 cores), run on hsqbench.planner.learned.cluster_ops, in pure torch.
$(LEARNED_STAMP): $(STAMP)
	$(PY) -c "import torch" 2>/dev/null || $(PY) -m pip install --quiet --retries 1 --no-deps $(TORCH_PIP)
	$(PY) -m pip install --quiet -e ".[learned]"
	$(PY) -m pip install --quiet --no-deps "cgn-pytorch==0.4.3"
	$(PY) -c "from hsqbench.planner.learned import network; network.import_backend(); print('contact-graspnet: installed')"
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

# A protocol's experiments (default: the paper's two) with all its planners, into runs/$(RUN)/
# (git-ignored: no command but `make results` writes a tracked file). The command builds the
# objects the protocol uses (and downloads missing YCB ones) before the first trial.
# Re-running continues the same run (--resume): finished trials are kept, so a killed benchmark
# loses nothing. RUN=name starts another run; PROTOCOL=quick (or a YAML path) another protocol (CONFIG=, its
# old name, still works for one release).
CONFIG ?= paper
PROTOCOL ?= $(CONFIG)
RUN ?= $(PROTOCOL)
benchmark: $(STAMP)
	$(PY) -m hsqbench.cli benchmark --protocol $(PROTOCOL) --run $(RUN) --jobs $(JOBS) --resume
	@echo "tables: runs/$(RUN)/tables.md"

# The built-in robustness sweeps (configs/protocols/sweeps/) on the isolated protocol, paper and unseen
# objects, into runs/sweeps/ (sweep.csv, one PNG per parameter, a run per point). With JOBS=2
# on a 2-core machine the unseen objects' three seeds took 49 min for hsq and antipodal alone;
# contact-graspnet, where installed, adds about 15 min per sweep on the paper's objects
# (SWEEP_PLANNERS="hsq single-sq antipodal" leaves it out; a later run adds it to the same runs).
# Rerunning resumes (--resume); SWEEP_ARGS="--seeds 0 1 2 3 4" scales them up (new runs, narrower bands).
SWEEPS ?= depth_noise calibration cameras pad_friction
SWEEP_PLANNERS ?=
SWEEP_ARGS ?=
sweeps: $(STAMP)
	$(PY) -m hsqbench.cli sweep $(SWEEPS) --run sweeps --jobs $(JOBS) --resume \
		$(if $(SWEEP_PLANNERS),--planners $(SWEEP_PLANNERS)) $(SWEEP_ARGS)

# The canonical runs behind README.md and docs/ (the list: configs/canonical.yaml), into
# results/, with every planner (the learned extra too) at this code version: about 6 hours with
# JOBS=2 on a 2-core machine. Resumable: rerunning continues where it stopped. ONLY="paper3 ycb3"
# makes some of them; RESULTS_ARGS="--dry-run" lists them with their expected time. Then the
# README's headline tables are rewritten from them (hsqbench.experiment.front_page).
ONLY ?=
RESULTS_ARGS ?=
results: $(LEARNED_STAMP)
	$(PY) -m hsqbench.experiment.canonical --jobs $(JOBS) $(if $(ONLY),--only $(ONLY)) $(RESULTS_ARGS)
	$(PY) -m hsqbench.experiment.front_page

clean:
	rm -rf $(VENV) build *.egg-info .pytest_cache .ruff_cache
