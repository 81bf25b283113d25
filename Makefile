# Two commands do all the set-up on a fresh machine:
#   make solve   -> creates .venv from requirements.lock on first use, runs the main job (headless MuJoCo solve)
#   make test    -> same venv, runs the test suite (notebooks included; ROS tests in real time): at most 12 minutes
#                   on 2 cores, each of its two phases printing its time
PY ?= python3
VENV ?= .venv
STAMP := $(VENV)/.installed
export NO_MKDOCS_2_WARNING ?= 1  # Material's end-of-life notice on every docs build

.PHONY: solve test test-all test-fast venv lint bench tables docs pictures clean lab

# ur3hanoi/version.py: the installed metadata's version is read from it (pyproject.toml's dynamic version).
$(STAMP): pyproject.toml requirements.lock tools/ensure-system-deps.sh ur3hanoi/version.py
	@$(PY) -c 'import sys; ok = (3, 11) <= sys.version_info[:2] <= (3, 13); ok or print(f"ur3hanoi: error: Python {sys.version.split()[0]} ($(PY)) is not supported: use Python 3.11, 3.12 or 3.13, e.g. make PY=python3.12"); sys.exit(not ok)'
	bash tools/ensure-system-deps.sh
	$(PY) -m venv $(VENV)
	$(VENV)/bin/pip install -q --upgrade pip
	$(VENV)/bin/pip install -q -c requirements.lock -e '.[dev]'
	touch $(STAMP)

venv: $(STAMP)

solve: $(STAMP)
	$(VENV)/bin/ur3hanoi solve --start 1 --end 3

# Two phases, each printing its slowest 25 tests and its wall time. The tests on the CPU clock run on every core (pytest-xdist); the
# ones on the wall clock (ROS 1, DDS, rclpy) and the wheel build run after them, WALL_WORKERS side by side: their
# processes mostly wait on real time (control cycles, DDS discovery, pip), and each test owns its master port, network
# namespace, files and processes (tests/support/ros_support.py, ros2_support.py, reaper.py). The tests of a module
# that share a module-scoped station stay on one worker (--dist loadgroup, tests/support/xdist_groups.py).
REALTIME := ros or dds or rclpy or packaging
WALL_WORKERS ?= 6
# $(call timed,NAME,COMMAND): COMMAND, then its wall time on stderr; the exit status is COMMAND's.
timed = start=$$(date +%s); $(2); code=$$?; echo "make $@: $(1) phase took $$(($$(date +%s) - start)) s (exit $$code)" >&2; exit $$code

# A sweep's further cases (marked `full`) run under make test-all only; each test says what make test still covers.
test: $(STAMP)
	@$(call timed,CPU-clock,$(VENV)/bin/python -m pytest -q --durations=25 -n auto -m "not ($(REALTIME) or full)")
	@$(call timed,wall-clock,$(VENV)/bin/python -m pytest -q --durations=25 -n $(WALL_WORKERS) --dist loadgroup -m "($(REALTIME)) and not full")

test-all: $(STAMP)
	@$(call timed,CPU-clock,$(VENV)/bin/python -m pytest -q -n auto -m "not ($(REALTIME))")
	@$(call timed,wall-clock,$(VENV)/bin/python -m pytest -q -n $(WALL_WORKERS) --dist loadgroup -m "$(REALTIME)")

# The tests that run on the CPU clock alone, without the long simulations.
test-fast: $(STAMP)
	$(VENV)/bin/python -m pytest -q -n auto -m "not ($(REALTIME) or slow or full)"

# Regenerate the shipped waypoint table from the two shipped calibrations (a test fails when it is stale).
tables: $(STAMP)
	$(VENV)/bin/ur3hanoi tables lab_sim --key sim_pos -o tables/lab2_data.yaml
	$(VENV)/bin/ur3hanoi tables lab_real --key real_pos -o tables/lab2_data.yaml

# The documentation site, built offline into site/ (not committed): open site/index.html. The command-line page is
# rewritten from the parser first; the pictures come from real runs (make pictures).
docs: $(STAMP)
	$(VENV)/bin/python tools/update_cli_page.py
	$(VENV)/bin/mkdocs build --strict --site-dir site

pictures: $(STAMP)
	$(VENV)/bin/python tools/make_pictures.py

lint: $(STAMP)
	$(VENV)/bin/ruff check .

bench: $(STAMP)
	$(VENV)/bin/python bench/run_all.py

# The notebooks in JupyterLab (installs the `notebooks` extra into the venv on first use).
lab: $(STAMP)
	$(VENV)/bin/pip install -q -c requirements.lock -e '.[notebooks]'
	$(VENV)/bin/jupyter lab notebooks/

clean:
	rm -rf $(VENV)
