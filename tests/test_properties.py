"""Property-based tests (hypothesis): any bytes, any numbers, any options give a result or one error.

For every reader: arbitrary bytes and arbitrary numeric tables give a :class:`Recording` or a
:class:`~motorlab.errors.MotorlabError`, never another exception. For every analysis, run as the
user runs it (``motorlab analyze``): valid rig files with hostile values written into random fields
(NaN, 1e308, 1e-300, 65535, 2³¹−1, ``1_0``, hex, empty), rows dropped or repeated, the file cut at a
random byte, give exit 0 or exit 2 with one error line, never exit 1 and never a traceback.

The example budget is fixed and small (``make test`` stays quick); ``HYPOTHESIS_PROFILE=long`` runs
many more examples.
"""

from __future__ import annotations

import contextlib
import io
import os
import tempfile
import warnings
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from motorlab import cli
from motorlab.errors import MotorlabError
from motorlab.io import READERS, read_any
from motorlab.rig import VirtualRig

settings.register_profile("quick", max_examples=6, deadline=None, derandomize=True,
                          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
settings.register_profile("long", max_examples=300, deadline=None,
                          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
PROFILE = os.environ.get("HYPOTHESIS_PROFILE", "quick")
READER_EXAMPLES = 40 if PROFILE == "quick" else 1000

# experiment -> (rig experiment, file name, rig settings, options of a valid run)
ANALYSES = {
    "spindown": ("spindown", "spindown.txt", {"on_time": 5.0, "coast_time": 10.0}, ("--cpr", "1120")),
    "spinup": ("spinup", "spinup.txt", {"duration": 5.0}, ("--cpr", "1120", "--inertia", "12.2")),
    "free-spinup": ("free-spinup", "free_spinup.csv", {}, ("--K", "0.7", "--current", "0.5 A")),
    "terminal": ("terminal", "terminal.csv", {}, ("--K", "0.7")),
    "lcr": ("lcr", "lcr.csv", {}, ()),
    "torque": ("torque", "torque.csv", {}, ()),
    "amplifier": ("amplifier", "amplifier.csv", {}, ()),
    "tachometer": ("tachometer", "tachometer.csv", {}, ()),
    "pulse": ("pulse", "pulse.csv", {}, ("--Ka", "1.96", "--K", "0.7")),
    "identify": ("transient", "transient.csv", {"duration": 1.0}, ("--cpr", "1120")),
    "feedforward": ("sysid", "sysid.json", {"quasistatic_duration": 6.0, "dynamic_duration": 2.0}, ()),
}

HOSTILE = st.sampled_from(["0", "-0", "1e308", "-1e308", "1e-300", "nan", "inf", "-inf", "65535", "2147483647",
                           "-1", "abc", "", "1_0", "0x10", "1e", "3.5", "-12"])
#: Options with hostile values an analysis may be given besides its valid ones.
OPTION_VALUES = st.sampled_from(["0", "1e308", "1e-300", "-1", "nan", "3 furlongs", "1_0", "0.5"])


@pytest.fixture(scope="module")
def rig_files(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("rig")
    rig = VirtualRig("neverest40", unit_seed=2, noise_seed=11)
    return {name: Path(rig.run(r, folder / f, **s).paths[0]) for name, (r, f, s, _) in ANALYSES.items()}


def _read_all(path: Path) -> None:
    """Every reader on ``path`` (and read_any): a Recording or a MotorlabError, nothing else."""
    for reader in (read_any, *READERS.values()):
        with contextlib.suppress(MotorlabError):
            reader(path)


@settings(max_examples=READER_EXAMPLES, deadline=None)
@given(content=st.binary(max_size=600), suffix=st.sampled_from([".txt", ".csv", ".json", ".wpilog"]))
def test_every_reader_on_any_bytes(content: bytes, suffix: str) -> None:
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / f"log{suffix}"
        path.write_bytes(content)
        _read_all(path)


NUMBER = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(min_value=-(2**63), max_value=2**63),
    HOSTILE,
)


@settings(max_examples=READER_EXAMPLES, deadline=None)
@given(
    header=st.sampled_from([
        "", "time_ms encoder_counts bus_voltage_V shunt_current_A\n", "time_s,voltage_V,current_A\n",
        "current_A,frequency_Hz\n", "time_ms\n", "L_uH,Q,DCR_ohm\n", "X,CH1,Start,Increment,\n",
    ]),
    rows=st.lists(st.lists(NUMBER, min_size=1, max_size=5), max_size=12),
    delimiter=st.sampled_from([",", " ", "\t", ";"]),
)
def test_every_reader_on_any_numbers(header: str, rows: list[list[object]], delimiter: str) -> None:
    text = header + "\n".join(delimiter.join(str(v) for v in row) for row in rows)
    with tempfile.TemporaryDirectory() as folder:
        for suffix in (".txt", ".csv"):
            path = Path(folder) / f"log{suffix}"
            path.write_text(text, encoding="utf-8")
            _read_all(path)


def _corrupt(text: str, data: st.DataObject) -> str:
    """Hostile values in random fields, rows dropped or repeated, the text cut at a random place."""
    lines = text.split("\n")
    for _ in range(data.draw(st.integers(0, 3), label="edits")):
        k = data.draw(st.integers(0, max(len(lines) - 1, 0)), label="line")
        action = data.draw(st.sampled_from(["field", "field", "drop", "repeat"]), label="action")
        if action == "drop":
            del lines[k]
        elif action == "repeat":
            lines.insert(k, lines[k])
        else:
            sep = "," if "," in lines[k] else " "
            fields = lines[k].split(sep)
            j = data.draw(st.integers(0, max(len(fields) - 1, 0)), label="field")
            fields[j] = data.draw(HOSTILE, label="value")
            lines[k] = sep.join(fields)
        if not lines:
            break
    out = "\n".join(lines)
    if data.draw(st.booleans(), label="cut"):
        out = out[: data.draw(st.integers(0, len(out)), label="cut at")]
    return out


def _run(argv: list[str]) -> tuple[int, str]:
    err = io.StringIO()
    with warnings.catch_warnings(), contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        warnings.simplefilter("default")  # as a user's Python: numerical warnings are printed, not raised
        try:
            code = cli.main(argv)
        except SystemExit as exc:  # argparse errors
            code = exc.code if isinstance(exc.code, int) else 1
    return code, err.getvalue()


@pytest.mark.parametrize("experiment", list(ANALYSES))
@settings(settings.get_profile(PROFILE))
@given(data=st.data())
def test_every_analysis_gives_a_result_or_one_error(experiment: str, rig_files, data: st.DataObject) -> None:
    source = rig_files[experiment]
    options = list(ANALYSES[experiment][3])
    if options and data.draw(st.booleans(), label="hostile option"):
        k = data.draw(st.integers(0, len(options) // 2 - 1), label="option")
        options[2 * k + 1] = data.draw(OPTION_VALUES, label="option value")
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / source.name
        path.write_text(_corrupt(source.read_text(), data))
        code, err = _run(["analyze", experiment, str(path), *options, "--json"])
    assert "Traceback" not in err
    assert code in (0, 2), err
    if code == 2:
        errors = [line for line in err.splitlines() if not line.startswith("motorlab: warning:")]
        assert len(errors) == 1, err
        assert errors[0].startswith("motorlab"), err
