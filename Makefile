# Two commands on a fresh machine: `make demo` and `make test`. Both create the virtual environment when missing.
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.skytrack-installed
PYTEST_ARGS ?= -q -n 2

.PHONY: demo test bench lint clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)

$(STAMP): pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[dev,envs,export,cluster,traffic]'
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/skytrack run demo --out runs/demo --video

test: $(STAMP)
	$(BIN)/python -m pytest $(PYTEST_ARGS)

bench: $(STAMP)
	$(BIN)/skytrack bench

lint: $(STAMP)
	$(BIN)/ruff check simulator vehicles autonomy worlds tests

clean:
	rm -rf $(VENV) runs build *.egg-info
