"""The fuzz suite's short, seeded profile (``make test``); ``make fuzz`` runs the long one (scripts/fuzz.py).

Hypothesis draws each case's choices (seed run, file or option mutation, special file, environment)
through :class:`HypothesisChooser`, so a failure shrinks to a small case; ``derandomize=True`` makes
the run the same on every machine. Each case runs in a forked child with a CPU-time and a memory
limit and is judged by ``fuzz_harness.judge`` (the README's promise on bad input). The app's upload
endpoints are fuzzed through Starlette's TestClient on ``create_app``.

``HYPOTHESIS_PROFILE=long`` gives many more examples (minutes).
"""

from __future__ import annotations

import os
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any, TypeVar

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

sys.path.insert(0, str(Path(__file__).parent))

from fuzz_app import app_case, app_client
from fuzz_cases import make_case, pick_seed
from fuzz_corpus import Seed, build, shared_real
from fuzz_harness import GOOD, run, warm
from fuzz_mutate import SPECIAL_FILES, mutators_for
from tests.real_data import not_found

T = TypeVar("T")
PROFILE = os.environ.get("HYPOTHESIS_PROFILE", "quick")
LONG = PROFILE == "long"
settings.register_profile("fuzz-quick", max_examples=14, deadline=None, derandomize=True, database=None,
                          suppress_health_check=list(HealthCheck))
settings.register_profile("fuzz-long", max_examples=400, deadline=None, derandomize=True, database=None,
                          suppress_health_check=list(HealthCheck))
FUZZ = settings.get_profile("fuzz-long" if LONG else "fuzz-quick")


class HypothesisChooser:
    """The fuzz choices drawn from hypothesis (so that a failing case shrinks)."""

    def __init__(self, data: st.DataObject):
        self.data = data

    def choice(self, options: Sequence[T]) -> T:
        return self.data.draw(st.sampled_from(list(options)))

    def integer(self, low: int, high: int) -> int:
        return self.data.draw(st.integers(low, high))


@pytest.fixture(scope="module")
def corpus(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, list[Seed]]:
    folder = tmp_path_factory.mktemp("fuzz-corpus")
    seeds = build(folder)
    warm()
    return folder, seeds


@pytest.fixture(scope="module")
def scratch(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("fuzz-cases")


def _assert_kept(outcome: Any, case: Any) -> None:
    if os.environ.get("FUZZ_VERBOSE"):
        print(f"\n{outcome.verdict:9} {outcome.seconds:5.1f} s {case.seed}: {case.mutation[:60]}: "
              f"{outcome.detail[:100]}")
    assert outcome.verdict in GOOD, (
        f"{outcome.verdict}: {outcome.detail}\n  seed {case.seed}, {case.mutation}\n  motorlab "
        f"{' '.join(case.argv)}\n  env {case.env} special {case.special}\n{outcome.stderr[-1500:]}"
    )


def _fast(seeds: list[Seed]) -> list[Seed]:
    """The seeds whose valid run takes about a second (the quick profile's budget)."""
    return seeds if LONG else [s for s in seeds if not s.slow]


@settings(FUZZ)
@given(data=st.data())
def test_files_options_and_environment(data: st.DataObject, corpus, scratch) -> None:
    """A mutated file, option or environment of any command: a result, one line, or a partial session."""
    folder, seeds = corpus
    c = HypothesisChooser(data)
    case = make_case(pick_seed(_fast(seeds), c), folder, c)
    _assert_kept(run(case, scratch, time_limit=60.0), case)


@settings(FUZZ.__class__(FUZZ, max_examples=4 if not LONG else 100))
@given(data=st.data())
def test_slow_readers(data: st.DataObject, corpus, scratch) -> None:
    """The whole-model fits (feedforward on SysId, Road Runner, FlightRecorder, wpilog; identify), mutated files."""
    folder, seeds = corpus
    c = HypothesisChooser(data)
    slow = [s for s in seeds if s.slow and not s.real]
    case = make_case(c.choice(slow), folder, c, modes=("file", "special", "options"))
    _assert_kept(run(case, scratch, time_limit=90.0), case)


def test_real_files_are_read_or_refused_in_one_line(corpus, scratch) -> None:
    """Every real file as it is: a result (or, for a table no analysis reads yet, one line)."""
    folder, seeds = corpus
    if shared_real() is None:
        pytest.skip(not_found("the shared real data (../shared/data/real)"))
    real = [s for s in seeds if s.real]
    assert any(s.name.startswith("real-") for s in real)
    chosen = real if LONG else [s for s in real if "any-outcome" in s.tags][:3]
    from fuzz_mutate import RandomChooser

    for seed in chosen:
        case = make_case(seed, folder, RandomChooser(0), modes=("valid",))
        _assert_kept(run(case, scratch, time_limit=120.0), case)


def test_every_special_file_and_mutator_is_exercised(corpus) -> None:
    """The mutators do change the files they are given (a fuzzer that mutates nothing tests nothing)."""
    from fuzz_mutate import RandomChooser

    folder, _seeds = corpus
    raw = (folder / "sysid.json").read_bytes()
    for name, mutator in mutators_for("json").items():
        changed = sum(mutator(raw, RandomChooser(k)) != raw for k in range(5))
        assert changed >= 3, name
    assert len(SPECIAL_FILES) >= 8


# ---- the app's upload endpoints ---------------------------------------------------------------------


@pytest.fixture(scope="module")
def client() -> Any:
    with app_client() as test_client:
        yield test_client


@settings(FUZZ.__class__(FUZZ, max_examples=5 if not LONG else 120))
@given(data=st.data())
def test_app_uploads(data: st.DataObject, client, corpus) -> None:
    """Mutated uploads, file names, fields and bodies to every upload endpoint: 2xx JSON, or 4xx {"error": one line}."""
    folder, seeds = corpus
    verdict, detail, what = app_case(client, folder, seeds, HypothesisChooser(data))
    if os.environ.get("FUZZ_VERBOSE"):
        print(f"\napp {verdict:9} {what}: {detail[:100]}")
    assert verdict in GOOD, f"{verdict}: {detail}\n  {what}"


def test_the_judge_catches_every_broken_promise(tmp_path: Path) -> None:
    """The oracle itself: each way of breaking the promise gets its verdict (a judge that passes all is no judge)."""
    from fuzz_harness import Case, judge

    case = Case(seed="s", mutation="m", argv=["analyze", "lcr", "a.csv", "--json"], blame="a.csv", json_output=True)
    before = {"a.csv": "h1"}

    def verdict(code: int, out: str = "", err: str = "", after: dict[str, str] | None = None,
                temp: list[Path] | None = None) -> str:
        return judge(case, code, out, err, before, after or dict(before), temp or [], tmp_path)[0]

    good = '{"parameters": {"R": {"value": 1.0}}, "warnings": []}'
    assert verdict(0, good) == "ok"
    assert verdict(2, err="motorlab: error: a.csv:3: not a number\n") == "refused"
    assert verdict(1, err="motorlab: internal error: KeyError\n") == "internal-error"
    assert verdict(2, err="Traceback (most recent call last):\n  x\nValueError\n") == "traceback"
    assert verdict(2, err="motorlab: error: not a number\n") == "unnamed-file"
    assert verdict(2, err="motorlab: error: a.csv: x\nmotorlab: error: y\n") == "not-one-line"
    assert verdict(0, good, after={"a.csv": "h2"}) == "modified-input"
    assert verdict(0, good, after={**before, "b.png": "h"}) == "stray-output"
    assert verdict(0, good, temp=[tmp_path / "tmpabc"]) == "stray-output"
    assert verdict(2, err="motorlab: error: a.csv: x\n", after={**before, "out.csv": "h"}) == "stray-output"
    assert verdict(0, '{"parameters": {"R": {"value": NaN}}}') == "bad-json"
    assert verdict(0, '{"parameters": {"R": {"value": -1.0}}, "warnings": []}') == "unwarned-physics"
    assert verdict(0, '{"parameters": {"R": {"value": -1.0}}, "warnings": ["R < 0: leads swapped?"]}') == "ok"
    assert verdict(0, good, err="motorlab: warning: RuntimeWarning: overflow (x.py:3)\n") == "python-warning"
    assert verdict(3, good) == "bad-exit"
