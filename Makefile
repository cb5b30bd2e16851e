# Two commands for a fresh machine (README):
#   make study   installs everything, then runs the full study (snakemake --cores 2)
#   make test    installs everything, then runs the test suite
# Everything is installed into .venv from pyproject.toml, at the versions constraints.txt pins; nothing by hand.

PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
CORES  ?= 2
STAMP  := $(VENV)/.installed
# every kernel in numba's cache, for the tests and the command line.  The study does not wait for it: its jobs
# compile only the kernels they use (make study measured 1,175 s cold, against 5 to 6 min of compiling then 1,034 s)
COMPILED := $(VENV)/.compiled

.PHONY: setup study paper test smoke lint docs screenshots bench peer clean chromium debug

$(STAMP): pyproject.toml constraints.txt
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -c constraints.txt -e '.[workflow,test,docs]'
	touch $(STAMP)

$(COMPILED): $(STAMP)
	@echo "compiling the engine's kernels into numba's cache, once (minutes: the README has the measured time)"
	$(BIN)/impact compile > /dev/null
	touch $(COMPILED)

setup: $(STAMP) $(COMPILED)

study: $(STAMP)
	@start=$$(date +%s); $(BIN)/snakemake --cores $(CORES); status=$$?; \
	echo "study wall time: $$(( $$(date +%s) - start )) s"; exit $$status

# the paper's scope alone (the stages beyond it stay configured but are skipped: config/paper.yaml)
paper: $(STAMP)
	@start=$$(date +%s); $(BIN)/snakemake --cores $(CORES) --configfile config/config.yaml config/paper.yaml; \
	status=$$?; echo "paper's scope wall time: $$(( $$(date +%s) - start )) s"; exit $$status

smoke: $(STAMP)
	$(BIN)/snakemake --cores $(CORES) --configfile config/smoke.yaml

# one job of the study again (the one that writes TARGET), with Snakemake's copy of its script kept: that copy
# holds the job's inputs, outputs, parameters and log, so it runs alone, under a debugger, as often as wanted
debug: $(STAMP)
	@test -n "$(TARGET)" || { echo "give the file the job writes: make debug TARGET=results/..."; exit 2; }
	$(BIN)/snakemake $(TARGET) --force --cores 1 --skip-script-cleanup $(SNAKEMAKE_ARGS)
	@echo "the job's script, to run alone: $$(ls -t .snakemake/scripts/*.py | head -1)"

# one worker a core (pytest-xdist), each test file on one worker so that its module fixtures run once, in
# collection order: the files marked long_file first (tests/conftest.py)
test: $(COMPILED) chromium
	$(BIN)/python -m pytest -q -n $(CORES) --dist loadfile --no-loadscope-reorder

lint: $(STAMP)
	$(BIN)/ruff check src tests benchmarks workflow/scripts tools
	$(BIN)/snakefmt --check Snakefile workflow
	$(BIN)/snakemake --lint

# the documentation site (the specification pages and the API reference), warnings as errors
docs: $(STAMP)
	$(BIN)/sphinx-build -W --keep-going -q -b html docs docs/_build/html
	@echo "docs/_build/html/index.html"

# both reports of a finished study as a reader sees them, 1280 px wide (headless Chromium): results/screenshots/
screenshots: $(STAMP) chromium
	$(BIN)/python tools/screenshots.py --results results

# each benchmark compiles what it times on its warm-up run (not timed), so it needs no `impact compile` first;
# it runs under the study's kernel sets, as the study does (impact.kernels)
bench: $(STAMP)
	$(BIN)/python -m impact.kernels benchmarks/bench_core.py

# the peers (not a runtime dependency): OpenSees, whose Linux wheel links the system's BLAS and LAPACK, installed
# here as root when missing (as chromium below); then the impact damper's and the yielding storeys' benchmarks
peer: $(STAMP)
	@if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1 && ! ldconfig -p | grep -q libblas.so.3; then \
	  (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq libblas3 liblapack3 >/dev/null); fi
	$(BIN)/pip install -q -e '.[peer]'
	$(BIN)/python -m impact.kernels benchmarks/bench_opensees.py
	$(BIN)/python -m impact.kernels benchmarks/bench_yield.py

clean:
	rm -rf results .snakemake

# headless Chromium for the report's browser test: installed as root when missing, else that test is skipped
chromium:
	@if command -v chromium >/dev/null 2>&1; then :; \
	elif [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
	  echo "installing chromium for the report's browser test (apt-get)"; \
	  (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null) \
	  || echo "chromium could not be installed: the report's browser test will be skipped"; \
	else echo "chromium missing and not root: the report's browser test will be skipped"; fi
