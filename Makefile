# Two entry points: `make demo` (the main job) and `make test` (the test suite).
# Both create .venv with the interpreter in $(PYTHON) and install the project into it.
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: demo test lint bench octave-check data clean

# The project's bytecode is compiled at install, as pip does for a wheel (an editable install
# leaves it to the first import, which machines with PYTHONDONTWRITEBYTECODE never write: each
# command then compiles the ~110 modules it imports, ≈ 0.3 s of `tiltbench gap`).
$(STAMP): pyproject.toml setup.py
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[rrd,test]"
	$(BIN)/python -m compileall -q bench calib > /dev/null
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/tiltbench demo --out demo-out --force

# One pytest worker per core (pytest-xdist), at most 4: some tests start worker processes of
# their own. Work stealing: an idle worker takes queued tests from a busy one, so the long
# Monte Carlo tests do not leave one worker running alone at the end (7.9 min against 8.4 on
# the 2-core VM, 2026-11-29). `make test` = the README's test command (CI runs it through
# .ci/run). Bytecode caching on for the run (PYTHONDONTWRITEBYTECODE emptied, as some
# machines set it): otherwise every worker re-rewrites the asserts of all ~200 test modules
# and every process the suite starts recompiles the project (collection alone: 15.4 s of CPU
# per worker without the cache, 5.4 s with it, 2026-11-30); __pycache__/ is git-ignored.
test: $(STAMP)
	PYTHONDONTWRITEBYTECODE= $(BIN)/python -m pytest -q -n auto --maxprocesses 4 --dist worksteal

lint: $(STAMP)
	$(BIN)/ruff check bench calib validation tests benchmarks tools

bench: $(STAMP)
	$(BIN)/python benchmarks/run.py
	$(BIN)/python benchmarks/cli_startup.py
	$(BIN)/python benchmarks/gap_scaling.py
	$(BIN)/python benchmarks/gap_command.py
	$(BIN)/python benchmarks/mc_speed.py
	$(BIN)/python benchmarks/csv_reader.py
	$(BIN)/python benchmarks/noise_speed.py

octave-check: $(STAMP)
	BIN=$(BIN) tools/octave_check.sh

# Regenerates the shipped datasets with the commands listed in data/README.md.
data: $(STAMP)
	sed -n '/^```sh$$/,/^```$$/p' data/README.md | grep '^tiltbench ' | \
	  (cd data && PATH="$(CURDIR)/$(BIN):$$PATH" bash -e > /dev/null)

clean:
	rm -rf $(VENV) demo-out .pytest_cache
