# Two commands on a fresh machine with Python 3.11 (see README):
#   make dry-run   set up .venv and run a dry run against the virtual rig
#   make test      set up .venv and run every test (the vcan stage through User-Mode Linux where needed)
#   make mutation  mutation testing of the safety code (slow, not in CI; benchmarks/README.md gives the kill rate)
PYTHON ?= $(shell command -v python3.11 || command -v python3)
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: setup dry-run simulate test test-fast bench mutation clean help

help:
	@sed -n 's/^#   /  /p' Makefile

$(STAMP): pyproject.toml
	@$(PYTHON) -c 'import sys; assert sys.version_info >= (3, 11), f"Python 3.11 or newer is needed, found {sys.version.split()[0]} at {sys.executable}; set PYTHON=/path/to/python3.11"'
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test,cluster]'
	@touch $(STAMP)

setup: $(STAMP)

dry-run: setup
	$(BIN)/harness dry-run

simulate: setup
	$(BIN)/harness simulate

test: setup
	scripts/run-tests

test-fast: setup
	$(BIN)/pytest -q -m "not slow and not vcan" -x

bench: setup
	$(BIN)/python benchmarks/bench_simulate.py

# mutmut (the "mutation" extra) mutates a copy of the tree in mutants/ and runs the safety unit tests against
# each mutant; the report lists the kill rate and every survivor. MUTATION_JOBS: parallel mutants.
# HARNESS_PROPERTY_EXAMPLES: hypothesis sequences per supervisor property (1000 in the suite; 100 here keeps
# a surviving mutant's run to seconds, so the kill rate is a lower bound).
MUTATION_JOBS ?= 2
HARNESS_PROPERTY_EXAMPLES ?= 100
mutation: setup
	$(BIN)/python -m pip install --quiet -e '.[test,cluster,mutation]'
	HARNESS_PROPERTY_EXAMPLES=$(HARNESS_PROPERTY_EXAMPLES) $(BIN)/python -m mutmut run --max-children $(MUTATION_JOBS)
	HARNESS_PROPERTY_EXAMPLES=$(HARNESS_PROPERTY_EXAMPLES) $(BIN)/python scripts/mutation_report.py

clean:
	rm -rf $(VENV) build *.egg-info .pytest_cache .hypothesis mutants
