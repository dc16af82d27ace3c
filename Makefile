# motorlab: make install | make test | make demo | make bench
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: install test lint demo bench clean

install: $(STAMP)

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test]'
	touch $(STAMP)

lint: install
	$(BIN)/ruff check src tests benchmarks
	$(BIN)/mypy

test: lint
	MPLBACKEND=Agg $(BIN)/pytest

demo: install
	MPLBACKEND=Agg $(BIN)/motorlab demo -o out/demo

bench: install
	MPLBACKEND=Agg $(BIN)/python benchmarks/run.py

clean:
	rm -rf $(VENV) out build src/*.egg-info
