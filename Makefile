# motorlab: make install | make test | make demo | make bench | make fuzz
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: install test lint demo bench fuzz clean

install: $(STAMP)

# uv (from PyPI) installs the same packages in a fifth of pip's time (16 s against 81 s for a new .venv,
# docs/ARCHITECTURE.md, "The test suite"); pip does it when uv cannot be had.
$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	{ $(BIN)/python -m pip install --quiet --disable-pip-version-check uv \
	  && $(BIN)/python -m uv pip install --quiet --python $(BIN)/python -e '.[test]'; } \
	|| { $(BIN)/python -m pip install --quiet --upgrade pip && $(BIN)/python -m pip install --quiet -e '.[test]'; }
	touch $(STAMP)

lint: install
	$(BIN)/ruff check src tests benchmarks
	$(BIN)/mypy

# The suite runs on every core (pytest-xdist; tests finish in any order and share nothing); BLAS on
# one thread per worker, so that two workers on two cores do not fight over four threads. Bytecode is
# written even where PYTHONDONTWRITEBYTECODE is set (uv installs none): otherwise every Python process
# the suite starts (workers, commands) compiles numpy, scipy, matplotlib and motorlab again, 8 s of CPU
# for one import of the CLI and the engine against 3 s (docs/ARCHITECTURE.md). The tests marked
# realtime (an emulated robot or meter on the wall clock: 2 min of waiting, 20 s of CPU) run in two
# processes of their own beside the workers (1 min 20 s on the wall clock; in one, 2 min 30 s, longer
# than the workers), and mypy (30 s of one CPU from a fresh clone) checks the types there too, in the
# moments the workers wait for a browser. make test fails when any of the three fails, and prints their
# reports after the workers' own. The suite is collected once first, beside mypy: from a fresh clone a
# collection compiles what it imports and rewrites the tests' asserts (13 s of CPU, 4 s once cached), which
# the four processes of the two lanes would otherwise each do at once (make test 8-10 s sooner).
PYTEST_ENV := MPLBACKEND=Agg OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 PYTHONDONTWRITEBYTECODE=
test: install
	$(BIN)/ruff check src tests benchmarks
	@mkdir -p out; $(BIN)/mypy > out/mypy.txt 2>&1 & typing=$$!; \
	$(PYTEST_ENV) $(BIN)/pytest --collect-only -q > /dev/null 2>&1; \
	$(PYTEST_ENV) $(BIN)/pytest -n 2 --dist worksteal -m realtime --durations=10 > out/realtime-tests.txt 2>&1 & waiting=$$!; \
	$(PYTEST_ENV) $(BIN)/pytest -n auto --dist worksteal -m "not realtime" --durations=30; tests=$$?; \
	wait $$waiting; timed=$$?; echo "tests on the wall clock: $$(tail -n 1 out/realtime-tests.txt)"; \
	if [ $$timed -ne 0 ]; then cat out/realtime-tests.txt; fi; \
	wait $$typing; typed=$$?; echo "mypy: $$(tail -n 1 out/mypy.txt)"; \
	if [ $$typed -ne 0 ]; then cat out/mypy.txt; fi; \
	exit $$(( tests != 0 ? tests : timed != 0 ? timed : typed ))

demo: install
	MPLBACKEND=Agg $(BIN)/motorlab demo -o out/demo

bench: install
	MPLBACKEND=Agg $(BIN)/python benchmarks/run.py

# The long fuzz run (docs/fuzz.md): 10,000 cases, resumable (out/fuzz/state.json), failures in
# out/fuzz/failures/; stops by itself after FUZZ_MINUTES (or on Ctrl-C / kill: the cases under way end,
# the state is saved). FUZZ_JOBS cases at once. E.g. make fuzz FUZZ_JOBS=2 FUZZ_ARGS="--cases 20000".
FUZZ_MINUTES ?= 240
FUZZ_JOBS ?= 1
fuzz: install
	MPLBACKEND=Agg nice -n 10 $(BIN)/python scripts/fuzz.py --minutes $(FUZZ_MINUTES) --jobs $(FUZZ_JOBS) $(FUZZ_ARGS)

clean:
	rm -rf $(VENV) out build src/*.egg-info
