"""The fuzz suite's short, seeded profile (``make test``); ``make fuzz`` runs the long one (scripts/fuzz.py).

Hypothesis draws each case's choices (seed run, file or option mutation, special file, environment)
through :class:`HypothesisChooser`, so a failure shrinks to a small case; ``derandomize=True`` makes
the run the same on every machine. Each case runs in a forked child with a CPU-time and a memory
limit and is judged by ``fuzz_harness.judge`` (the README's promise on bad input). The app's upload
endpoints are fuzzed through Starlette's TestClient on ``create_app``.

``HYPOTHESIS_PROFILE=long`` gives many more examples (minutes).
"""

from __future__ import annotations

import io
import json
import os
import sys
import zipfile
from collections.abc import Sequence
from pathlib import Path
from typing import Any, TypeVar

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

sys.path.insert(0, str(Path(__file__).parent))

from fuzz_cases import make_case, pick_seed
from fuzz_corpus import Seed, build, shared_real
from fuzz_harness import GOOD, run, warm
from fuzz_mutate import SPECIAL_FILES, mutators_for

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
    real = [s for s in seeds if s.real]
    assert any(s.name.startswith("real-") for s in real)
    chosen = real if LONG else [s for s in real if "any-outcome" in s.tags][:3]
    from fuzz_mutate import RandomChooser

    for seed in chosen:
        case = make_case(seed, folder, RandomChooser(0), modes=("valid",))
        _assert_kept(run(case, scratch, time_limit=120.0), case)
    if shared_real() is None:
        pytest.skip("../shared/data/real is absent (set MOTORLAB_REAL_DATA): only tests/data/real was fuzzed")


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
    import warnings

    with warnings.catch_warnings():  # starlette would rather have "httpx2"; httpx is what the project installs
        warnings.simplefilter("ignore")
        from starlette.testclient import TestClient

    from motorlab.ui.app import create_app

    with TestClient(create_app(), base_url="http://127.0.0.1:8765") as test_client:
        yield test_client


def _assert_app_kept(response: Any, what: str) -> None:
    assert response.status_code < 500, f"{what}: {response.status_code} {response.text[:500]}"
    if response.headers.get("content-type", "").startswith("application/json"):
        body = json.loads(response.text, parse_constant=lambda name: pytest.fail(f"{what}: {name} in the JSON"))
        if response.status_code >= 400:
            assert isinstance(body.get("error"), str), (what, body)
            assert "\n" not in body["error"], (what, body)
            assert "Traceback" not in body["error"], (what, body)
            assert body["error"].strip(), what


APP_FORMS = ("analyze", "detect", "tune", "characterize", "garbage-body", "zip")


@settings(FUZZ.__class__(FUZZ, max_examples=5 if not LONG else 120))
@given(data=st.data())
def test_app_uploads(data: st.DataObject, client, corpus) -> None:
    """Mutated uploads, fields and bodies to every upload endpoint: 200 with JSON, or 4xx {"error": one line}."""
    folder, seeds = corpus
    c = HypothesisChooser(data)
    form = c.choice(list(APP_FORMS))
    fast = [s for s in _fast(seeds) if s.command[0] == "analyze" and s.files and not s.real]
    seed = c.choice(fast)
    name = seed.files[0]
    content = (folder / name).read_bytes()
    if c.choice([True, True, False]):
        mutator = c.choice(sorted(mutators_for(seed.kind)))
        content = mutators_for(seed.kind)[mutator](content, c)
    filename = c.choice([name, "../../etc/passwd", "", ".hidden.csv", "a" * 300 + ".csv", "x\x00y.csv", "é.csv"])
    fields = {opt[2:]: val for opt, val in zip(seed.options[::2], seed.options[1::2], strict=False)}
    if c.choice([False, True]):
        fields[c.choice(["cpr", "K", "inertia", "current", "plot", "output", "no-such"])] = c.choice(
            ["9**9**9", "2**1024", "1e-12", "", "nan", "-1", "\x00"])
    what = f"{form} {seed.name} {filename!r} {fields}"
    if form == "garbage-body":
        response = client.post(f"/api/analyze/{seed.command[1]}", content=content[:5000],
                               headers={"content-type": c.choice(["multipart/form-data; boundary=x",
                                                                  "application/json", "text/plain"])})
    elif form == "zip":
        buffer = io.BytesIO()
        with zipfile.ZipFile(buffer, "w") as zf:
            zf.writestr(c.choice([name, "../evil.csv", "/abs.csv", "d/" * 50 + "x.csv"]), content)
        raw = buffer.getvalue()
        raw = raw if c.choice([True, False]) else mutators_for("binary")["flip-bytes"](raw, c)
        response = client.post("/api/detect", files=[("file", ("logs.zip", raw))])
    elif form == "detect":
        response = client.post("/api/detect", files=[("file", (filename, content))])
    elif form == "tune":
        response = client.post("/api/tune", files=[("params", ("params.json", content))],
                               data={"kv": c.choice(["0.12", "9**9**9", "nan"])})
    elif form == "characterize":
        toml = (folder / "session.toml").read_bytes()
        toml = mutators_for("toml")[c.choice(sorted(mutators_for("toml")))](toml, c)
        files = [("file", ("session.toml", toml))] + [("file", (n, (folder / n).read_bytes()))
                                                       for n in ("lcr.csv", "terminal.csv", "torque.csv")]
        response = client.post("/api/characterize", files=files)
    else:
        response = client.post(f"/api/analyze/{seed.command[1]}", files=[("file", (filename, content))], data=fields)
    _assert_app_kept(response, what)
