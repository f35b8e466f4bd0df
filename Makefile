# `make run` and `make test` work on a fresh clone: the first use creates .venv and installs
# the pinned requirements and this package (editable).
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: run test lint unit bench cuda-check gpu-check gpu-check-cpu clean

$(STAMP): requirements.txt setup.py package.xml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -r requirements.txt
	$(BIN)/python -m pip install --quiet --no-deps -e .
	touch $(STAMP)

# the main job, for a 2-core CPU: DamBreak 1's laboratory column at dx = 3 cm with the obstruction in a
# 1.5 cm zone, through the impact (its peak force at 0.35 s) to 0.6 s, recorded and analysed
RUN_DIR ?= runs/make-run
run: $(STAMP)
	rm -rf $(RUN_DIR)
	$(BIN)/gpusph-run dambreak1_lab_zoned --set dx=0.03 --set end_time=0.6 --out $(RUN_DIR)
	$(BIN)/gpusph-analyze $(RUN_DIR)

# every test, the lint among them (tests/test_lint.py); markers unit, physics, ros, study (pytest.ini).
# One pass, a pytest-xdist worker per core, each test file on one worker (--dist loadfile): a file's
# fixtures wider than a test (a settled tank, a bore, a node) are made once, and its node, recording
# and study tests, which time what their nodes answer, run one after another (each file's nodes on
# DDS domains of its own; every one of their timing bounds holds on a loaded 2-core machine). A
# unit or physics test runs on its worker's core alone (tests/conftest.py). The slowest are listed,
# to watch the 15-minute budget on 2 cores.
test: $(STAMP)
	$(BIN)/python -m pytest -q -n auto --dist loadfile --durations=20 tests

lint: $(STAMP)
	$(BIN)/ruff check .

# the fast tests alone (under a minute)
unit: $(STAMP)
	$(BIN)/python -m pytest -q -m unit tests

bench: $(STAMP)
	$(BIN)/python bench/solver.py
	$(BIN)/python bench/node.py

# every kernel of the package built for CUDA (sm_75, the oldest this Warp's NVRTC takes, and sm_90)
# through Warp's NVRTC with no GPU, its PTX read for float atomic adds and float64 arithmetic
# (bench/cuda_code.py; up to a minute a force pass and architecture, too long for `make test`:
# docs/results/cuda_code.md)
cuda-check: $(STAMP)
	$(BIN)/python bench/cuda_code.py --out runs/cuda_code.csv

# on a machine where Warp sees CUDA: tests, step counts, graph against eager, benchmarks and DamBreak 1
# at 1 cm on cuda:0, one report (runs/gpu-check/report.md); elsewhere it says no CUDA device was found
# and exits 0. gpu-check-cpu rehearses the same report on the CPU, shrunk (under 3 minutes).
gpu-check: $(STAMP)
	$(BIN)/python bench/gpu_check.py

gpu-check-cpu: $(STAMP)
	$(BIN)/python bench/gpu_check.py --cpu --out runs/gpu-check-cpu

clean:
	rm -rf $(VENV) build *.egg-info
