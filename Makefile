# `make run` and `make test` work on a fresh clone: the first use creates .venv and installs
# the pinned requirements and this package (editable).
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: run test bench clean

$(STAMP): requirements.txt setup.py package.xml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -r requirements.txt
	$(BIN)/python -m pip install --quiet --no-deps -e .
	touch $(STAMP)

# the main job, coarse enough for a 2-core CPU: DamBreak 1 at dx = 3 cm for 1 s, recorded and analysed
RUN_DIR ?= runs/make-run
run: $(STAMP)
	rm -rf $(RUN_DIR)
	$(BIN)/gpusph-run dambreak1_thesis --set dx=0.03 --set end_time=1.0 --out $(RUN_DIR)
	$(BIN)/gpusph-analyze $(RUN_DIR)

test: $(STAMP)
	$(BIN)/python -m pytest -q tests

bench: $(STAMP)
	$(BIN)/python bench/solver.py
	$(BIN)/python bench/node.py

clean:
	rm -rf $(VENV) build *.egg-info
