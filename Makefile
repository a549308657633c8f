# mtmc — every target sets itself up on a fresh machine (Python 3.11, pip, make).
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed-dev

.PHONY: demo test lint typecheck unit fuzz bench clean vendor

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[dev]"
	touch $(STAMP)

## demo: run the shipped studies into mtmc-demo/ (index.html links each report)
demo: $(STAMP)
	$(BIN)/python -m mtmc.demo

## test: lint (ruff), type-check (mypy), then the unit, reference and doc tests (pytest, with coverage)
test: lint typecheck unit

lint: $(STAMP)
	$(BIN)/ruff check src tests benchmarks examples docs/tutorials
	$(BIN)/ruff format --check src tests benchmarks examples docs/tutorials

typecheck: $(STAMP)
	$(BIN)/mypy

# coverage of src/mtmc by the tests, with a floor; uncovered lines listed per file. The tests
# run on every core (pytest-xdist), a test file to a worker, so that a module's fixtures (a
# demo run, a rendered report) are computed once; TEST_WORKERS=0 runs them in this process.
# Python's bytecode caches (__pycache__, ignored by git) are written even where the
# environment sets PYTHONDONTWRITEBYTECODE: the two workers and the processes the tests start
# (the CLI's exit and signal tests) import mtmc, and without the caches each compiles it
# again (a clean clone's make test: 673 s of CPU without them, 626 s with them).
COV_FLOOR ?= 93
TEST_WORKERS ?= auto
unit: $(STAMP)
	env -u PYTHONDONTWRITEBYTECODE $(BIN)/pytest -n $(TEST_WORKERS) --dist loadfile --cov=mtmc --cov-report=term-missing:skip-covered --cov-fail-under=$(COV_FLOOR)

## fuzz: hostile input at a larger budget: the properties of tests/fuzz (2000 cases each, on
## every core), then a random campaign over every reader and command that reads a file, with
## counts by outcome
FUZZ_CASES ?= 2000
fuzz: $(STAMP)
	MTMC_FUZZ_EXAMPLES=$(FUZZ_CASES) $(BIN)/pytest tests/fuzz -n $(TEST_WORKERS) --dist load --no-cov -p no:cacheprovider -q
	cd tests/fuzz && ../../$(BIN)/python mtmc_fuzz.py --cases $(FUZZ_CASES) --seed 1 --quiet

## bench: the benchmarks of benchmarks/ (installs suncal for the side-by-side comparison)
bench: $(STAMP)
	$(BIN)/python -m pip install --quiet -e ".[dev,bench]"
	$(BIN)/python benchmarks/run.py

## vendor: refresh the workbench's cytoscape.js from npm (needs Node's npm; nothing else does)
CYTOSCAPE ?= 3.34.4
VENDOR_DIR := src/mtmc/workbench/static/vendor
vendor:
	rm -rf .vendor-tmp && mkdir .vendor-tmp
	cd .vendor-tmp && npm pack --silent cytoscape@$(CYTOSCAPE) >/dev/null && tar xzf cytoscape-*.tgz
	cp .vendor-tmp/package/dist/cytoscape.esm.min.mjs $(VENDOR_DIR)/cytoscape.esm.min.mjs
	cp .vendor-tmp/package/LICENSE $(VENDOR_DIR)/cytoscape.LICENSE.txt
	$(PYTHON) -c 'import hashlib, json, sys; d = sys.argv[1]; p = json.load(open(".vendor-tmp/package/package.json")); f = "cytoscape.esm.min.mjs"; json.dump({f: {"package": "cytoscape", "version": p["version"], "license": p["license"], "licence_file": "cytoscape.LICENSE.txt", "source": "npm pack cytoscape@" + p["version"] + ": dist/" + f, "sha256": hashlib.sha256(open(d + "/" + f, "rb").read()).hexdigest()}}, open(d + "/VENDOR.json", "w"), indent=2); open(d + "/VENDOR.json", "a").write("\n")' $(VENDOR_DIR)
	rm -rf .vendor-tmp

clean:
	rm -rf $(VENV) .pytest_cache .mypy_cache .ruff_cache mtmc-demo
