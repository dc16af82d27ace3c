"""``motorlab acquire lcr`` against the project's DE-5000 emulator on a localhost socket, then ``analyze lcr``."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from motorlab.acquire.emulator import DE5000Emulator, winding_stream
from motorlab.acquire.es51919 import encode
from motorlab.acquire.lcr import acquire_lcr
from motorlab.cli import main

#: The emulated meter sends its readings on the wall clock: make test runs these beside the others (the Makefile).
pytestmark = pytest.mark.realtime


def _truth(seed: int, n: int = 6) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    inductance = 2.4e-3 * rng.uniform(0.85, 1.15, n)  # a commutator's spread over shaft positions
    q = 8.9 * rng.uniform(0.95, 1.05, n)
    return inductance, q


@pytest.mark.parametrize(
    ("secondary", "parallel", "seed"),
    [("quality_factor", False, 1), ("dissipation_factor", False, 2), ("phase_angle", False, 3),
     ("resistance", False, 4), ("resistance", True, 5)],
)
def test_acquire_then_analyze_recovers_what_was_streamed(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], secondary: str, parallel: bool, seed: int
) -> None:
    inductance, q = _truth(seed)
    stream = winding_stream(inductance, q, secondary=secondary, parallel=parallel, garbage=23, overloads=2, seed=seed)
    out = tmp_path / "lcr.csv"
    with DE5000Emulator(stream, chunk=5) as meter:
        code = main(["acquire", "lcr", "--port", meter.url, "--readings", "6", "-o", str(out)])
    assert code == 0
    capsys.readouterr()
    assert main(["analyze", "lcr", str(out), "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    params = result["parameters"] if "parameters" in result else result[0]["parameters"]
    if parallel:  # the analysis converts the parallel Lp to the series Ls = Lp·Q²/(1+Q²)
        inductance = inductance * q**2 / (1 + q**2)
    r_streamed = 2 * math.pi * 1000.0 * inductance / q
    assert params["L"]["value"] == pytest.approx(np.mean(inductance), rel=0.01)
    assert params["R"]["value"] == pytest.approx(np.mean(r_streamed), rel=0.03)


def test_dc_resistance_readings_and_mode_lock(tmp_path: Path) -> None:
    dcr = [1.62, 1.71, 1.58, 1.66]
    stream = b"".join(encode(("dc_resistance", r), frequency=0.0) for r in dcr[:2])
    stream += encode(("inductance", 2e-3), ("quality_factor", 9.0))  # the user turned the dial: skipped
    stream += b"".join(encode(("dc_resistance", r), frequency=0.0) for r in dcr[2:])
    out = tmp_path / "dcr.csv"
    messages: list[str] = []
    with DE5000Emulator(b"".join(encode(("dc_resistance", r), frequency=0.0) for r in dcr)) as meter:
        assert acquire_lcr(meter.url, str(tmp_path / "auto.csv"), readings=4).kind == "dc_resistance"
    with DE5000Emulator(stream) as meter:
        log = acquire_lcr(meter.url, str(out), readings=4, kind="dc_resistance", report=messages.append)
    assert log.kind == "dc_resistance"
    assert log.rows == 4
    from motorlab.analyses.lcr import lcr
    from motorlab.io.csv_table import read_csv

    result = lcr(read_csv(out))
    assert result.parameters["R_dc"].value == pytest.approx(np.mean(dcr), rel=1e-6)
    assert any("inductance reading in a file of dc_resistance" in m for m in messages)


def test_auto_prefers_inductance_in_a_mixed_stream(tmp_path: Path) -> None:
    stream = b"".join(encode(("dc_resistance", 1.7), frequency=0.0) + encode(("inductance", v), ("quality_factor", 9.0))
                      for v in (2.0e-3, 2.1e-3, 2.2e-3))
    with DE5000Emulator(stream) as meter:
        log = acquire_lcr(meter.url, str(tmp_path / "m.csv"), readings=3)
    assert log.kind == "inductance"
    assert log.rows == 3


def test_interactive_discards_the_reading_taken_while_turning(tmp_path: Path) -> None:
    first = encode(("inductance", 1e-3), ("quality_factor", 5.0))  # measured while the shaft turned
    steady = encode(("inductance", 2e-3), ("quality_factor", 5.0))
    prompts: list[str] = []
    answers = iter(["", "q"])

    def ask(text: str) -> str:
        prompts.append(text)
        return next(answers)

    with DE5000Emulator(first, chunk=17, interval=0.01, repeat=steady) as meter:  # a meter left on
        log = acquire_lcr(meter.url, str(tmp_path / "i.csv"), readings=3, interactive=True, ask=ask)
    assert log.rows == 1
    assert len(prompts) == 2
    assert "position 1 of 3" in prompts[0]
    text = (tmp_path / "i.csv").read_text()
    assert "2000,5,1000,1," in text  # the second packet after Enter, at position 1


def test_bad_input_is_one_line_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "x.csv"
    with DE5000Emulator(b"\x55" * 200) as meter:  # a talking port that is not a DE-5000
        assert main(["acquire", "lcr", "--port", meter.url, "--readings", "2", "--timeout", "0.5",
                     "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "no usable DE-5000 reading in 0.5 s" in err
    assert "no 17-byte packet" in err
    assert len(err.splitlines()) == 1
    assert not out.exists()
    only_ol = encode(("inductance", "OL"), ("quality_factor", "blank")) * 5
    with DE5000Emulator(only_ol) as meter:
        assert main(["acquire", "lcr", "--port", meter.url, "--timeout", "0.5", "-o", str(out)]) == 2
    assert "5 × display OL" in capsys.readouterr().err
    assert main(["acquire", "lcr", "--port", "socket://127.0.0.1:1", "-o", str(out)]) == 2
    assert "cannot open" in capsys.readouterr().err
    out.write_text("keep me\n")
    assert main(["acquire", "lcr", "--port", "socket://127.0.0.1:1", "-o", str(out)]) == 2
    assert "not overwriting" in capsys.readouterr().err
    assert out.read_text() == "keep me\n"
    with pytest.raises(SystemExit) as exc:
        main(["acquire", "lcr", "--port", "x", "--readings", "0", "-o", str(out)])
    assert exc.value.code == 2


def test_cli_interactive_reads_enter_from_stdin(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    import io

    steady = encode(("inductance", 3e-3), ("quality_factor", 7.0))
    monkeypatch.setattr("sys.stdin", io.StringIO("\n\n"))  # two positions, then end of input stops
    out = tmp_path / "p.csv"
    with DE5000Emulator(b"", chunk=17, interval=0.01, repeat=steady) as meter:
        assert main(["acquire", "lcr", "--port", meter.url, "--interactive", "--readings", "3", "-o", str(out)]) == 0
    captured = capsys.readouterr()
    assert "wrote 2 L/Q readings" in captured.out
    assert "position 3 of 3" in captured.err
    rows = [line.split(",") for line in out.read_text().splitlines() if line[0].isdigit()]
    assert [r[3] for r in rows] == ["1", "2"]  # the shaft positions


def test_a_meter_that_stops_answering_keeps_the_readings_taken_and_says_so(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    inductance, q = _truth(7, n=3)
    out = tmp_path / "lcr.csv"
    with DE5000Emulator(winding_stream(inductance, q, seed=7)) as meter:
        code = main(["acquire", "lcr", "--port", meter.url, "--readings", "6", "--timeout", "1", "-o", str(out)])
    assert code == 2
    err = [line for line in capsys.readouterr().err.strip().splitlines() if not line.startswith("reading ")]
    assert len(err) == 1  # the readings as they came, then one error line
    assert f"the 3 reading(s) taken are kept in {out}" in err[0]
    assert len([line for line in out.read_text().splitlines() if line and line[0].isdigit()]) == 3
