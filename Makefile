# The README's two commands: `make figures` (the main job) and `make test`.
# Each bootstraps a virtual environment in .venv with the package installed.

PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.chainrun-installed
CONFIGS := $(wildcard configs/*.toml configs/*.yaml)

.PHONY: test figures simulate clean-results help

help:
	@echo "make test     install into .venv (if needed) and run the test suite"
	@echo "make figures  run every experiment in configs/ into results/"

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test]'
	touch $@

test: $(STAMP)
	$(BIN)/python -m pytest -n 2 -q

simulate: $(STAMP)
	@for c in $(CONFIGS); do $(BIN)/chainrun simulate $$c --force || exit 1; done

figures: simulate

clean-results:
	rm -rf results
