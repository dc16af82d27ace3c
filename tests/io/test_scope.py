"""Oscilloscope readers: cursor times, Rigol waveform exports, Schmitt-trigger edge detection."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from motorlab.errors import LogFormatError, OptionError
from motorlab.io.scope import find_rising_edges, read_scope_times, read_scope_waveform

# Rising mid-level crossings of CH1 in tests/data/scope/rigol_ds1054z.csv (see tests/data/README.md).
RIGOL_EDGES = np.array([0.20, 1.30, 2.20, 3.00, 3.70, 4.35, 4.95]) * 1e-3


def test_cursor_times_in_ms(data_dir):
    rec = read_scope_times(data_dir / "scope/edges_ms.csv")
    np.testing.assert_allclose(rec.time, [0, 1.412e-3, 2.310e-3, 3.005e-3, 3.601e-3, 4.130e-3])
    np.testing.assert_array_equal(rec["counts"], np.arange(6))
    assert rec.metadata["kind"] == "edges"
    assert rec.metadata["format"] == "scope-times"
    assert rec.lines.tolist() == [2, 3, 4, 5, 6, 7]


def test_cursor_times_in_s_with_metadata_and_trailing_commas(data_dir):
    rec = read_scope_times(data_dir / "scope/edges_s.csv")
    np.testing.assert_allclose(rec.time, [0, 1.412e-3, 2.310e-3])
    assert rec.metadata["motor"] == "NeveRest 60 bare"


def test_plain_numbers_are_taken_as_milliseconds(data_dir):
    rec = read_scope_times(data_dir / "scope/edges_plain.txt")
    np.testing.assert_allclose(rec.time, [0, 1.412e-3, 2.310e-3, 3.005e-3])
    assert "milliseconds" in rec.metadata["note"]


@pytest.mark.parametrize(
    ("name", "pattern"),
    [
        ("edges_backwards.csv", r"edges_backwards\.csv:4: edge times must increase"),
        ("edges_two_columns.csv", r"edges_two_columns\.csv:1: expected a single column"),
    ],
)
def test_bad_cursor_files(data_dir, name, pattern):
    with pytest.raises(LogFormatError, match=pattern):
        read_scope_times(data_dir / "scope" / name)


def test_cursor_nan_and_empty(tmp_path):
    path = tmp_path / "edges.csv"
    path.write_text("time_ms\n0\n1.5\ninf\n")
    with pytest.raises(LogFormatError, match=r"edges\.csv:4: time_ms: 'inf' is not a finite number"):
        read_scope_times(path)
    path.write_text("time_ms\n")
    with pytest.raises(LogFormatError, match="no edge times"):
        read_scope_times(path)


def test_rigol_export_edges_are_interpolated(data_dir):
    rec = read_scope_waveform(data_dir / "scope/rigol_ds1054z.csv")
    assert rec.metadata["layout"] == "rigol"
    assert rec.metadata["channel"] == "CH1"
    assert rec.metadata["sample_interval"] == pytest.approx(1e-5)
    # Values are printed with 3 significant digits: 5 mV on a 66 V/ms ramp is < 0.1 µs.
    np.testing.assert_allclose(rec.time, RIGOL_EDGES, atol=1e-7)
    np.testing.assert_array_equal(rec["counts"], np.arange(RIGOL_EDGES.size))
    assert rec.metadata["levels"]["threshold"] == pytest.approx(1.65)
    # Each edge points at a line of the file: index k is on line k + 3.
    index = np.rint((RIGOL_EDGES + 1e-3) / 1e-5)
    assert np.all(np.abs(rec.lines - (index + 3)) <= 1)


def test_rigol_flat_channel_has_no_edges(data_dir):
    with pytest.raises(LogFormatError, match="no rising edge found in CH2"):
        read_scope_waveform(data_dir / "scope/rigol_ds1054z.csv", channel="CH2")
    with pytest.raises(OptionError, match="CH3"):
        read_scope_waveform(data_dir / "scope/rigol_ds1054z.csv", channel="CH3")


def test_generic_table_waveform(data_dir):
    rec = read_scope_waveform(data_dir / "scope/waveform_table.csv")
    assert rec.metadata["layout"] == "table"
    np.testing.assert_allclose(rec.time, RIGOL_EDGES, atol=1e-9)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_schmitt_trigger_ignores_noise_and_finds_every_edge(seed):
    rng = np.random.default_rng(seed)
    dt = 2e-6
    time = np.arange(0, 0.02, dt)
    # A quadrature channel of a motor spinning up: phase grows quadratically; rising edges where
    # the phase passes whole cycles.
    cycles = 0.5 + 0.6e6 * time**2  # starts low; high while the fractional part is below 1/2
    clean = np.where((cycles % 1.0) < 0.5, 3.3, 0.0)
    clean = np.convolve(clean, np.ones(5) / 5, mode="same")  # finite rise time
    volts = clean + rng.normal(0, 0.25, time.size)  # noise big enough to cross a single threshold
    edges, levels = find_rising_edges(time, volts)
    true = np.sqrt((np.arange(1, int(cycles[-1]) + 1) - 0.5) / 0.6e6)  # cycles passes a whole number
    true = true[(true > 4 * dt) & (true < time[-1] - 4 * dt)]
    assert edges.size == true.size
    assert np.max(np.abs(edges - true)) < 2 * dt  # measured: max 1.2 dt, rms 0.45 dt (seeds 0-2)
    assert levels["low"] < levels["threshold"] < levels["high"]
    # Without hysteresis the noise makes spurious edges: the trigger window is what prevents them.
    noisy, _ = find_rising_edges(time, volts, hysteresis=0.0)
    assert noisy.size > true.size


def test_bad_waveform_files(tmp_path):
    path = tmp_path / "w.csv"
    path.write_text("X,CH1,Start,Increment,\nSequence,Volt,-1e-3,0\n0,1,\n1,2,\n")
    with pytest.raises(LogFormatError, match="Increment must be positive"):
        read_scope_waveform(path)
    path.write_text("X,CH1,Start,Increment,\nSequence,Volt,-1e-3,1e-6\n0,1,\n1,****,\n2,1,\n")
    with pytest.raises(LogFormatError, match=r"w\.csv:4: CH1: '\*\*\*\*' is not a number"):
        read_scope_waveform(path)
    path.write_text("index,volts\n0,1\n1,2\n")
    with pytest.raises(LogFormatError, match="not a waveform export"):
        read_scope_waveform(path)


def _square_wave_export(path, n: int = 3000, *, rows=None, newline: str = "\n", end: str = "\n") -> None:
    """A Rigol export of a 3.3 V square wave of period 100 samples (rising edges at 50, 150, ...)."""
    k = np.arange(n)
    volts = np.where((k // 50) % 2 == 1, 3.3, 0.0) + 0.01 * np.sin(k)
    lines = ["X,CH1,Start,Increment,", "Sequence,Volt,-1.000000e-03,1.000000e-05,"]
    lines += rows if rows is not None else [f"{i},{v:.4e}," for i, v in zip(k, volts, strict=True)]
    path.write_text(newline.join(lines) + end, newline="")


@pytest.mark.parametrize("chunk", [64, 1000, 1 << 23])
def test_waveform_read_in_chunks_gives_what_a_whole_read_gives(tmp_path, monkeypatch, chunk):
    # Chunks of a few lines (a row cut across chunk boundaries, comments and blank lines inside some
    # chunks, a truncated last line) give the same edges and lines as the file read whole.
    from motorlab.io import _chunks
    from motorlab.io.scope import _samples_in_memory, find_rising_edges

    k = np.arange(3000)
    volts = np.where((k // 50) % 2 == 1, 3.3, 0.0) + 0.01 * np.sin(k)
    rows = [f"{i},{v:.4e}," for i, v in zip(k, volts, strict=True)]
    rows[700:700] = ["# a note the user typed", ""]
    rows.append("3000,3.3e")  # the writer was cut off
    path = tmp_path / "w.csv"
    _square_wave_export(path, rows=rows, end="")
    monkeypatch.setattr(_chunks, "CHUNK", chunk)
    rec = read_scope_waveform(path)
    whole = _samples_in_memory(path, None)
    edges, _ = find_rising_edges(whole.time, whole.volts)
    np.testing.assert_allclose(rec.time, edges, rtol=0, atol=1e-12)
    expected = np.searchsorted(whole.time, edges)
    np.testing.assert_array_equal(rec.lines, whole.lines[expected])
    assert rec.metadata["n_samples"] == 3000
    assert rec.metadata["sample_interval"] == pytest.approx(1e-5)
    assert rec.lines[0] == 3 + 50  # the sample after the first crossing; no comment before it


def test_waveform_with_gaps_in_the_index_and_crlf(tmp_path, monkeypatch):
    from motorlab.io import _chunks

    k = np.concatenate([np.arange(1000), np.arange(1100, 3000)])  # a gap: the indices are kept
    volts = np.where((k // 50) % 2 == 1, 3.3, 0.0)
    path = tmp_path / "w.csv"
    _square_wave_export(path, rows=[f"{i},{v:.4e}," for i, v in zip(k, volts, strict=True)], newline="\r\n")
    monkeypatch.setattr(_chunks, "CHUNK", 4096)
    rec = read_scope_waveform(path)
    rises = [i for i in range(1, k.size) if volts[i] > volts[i - 1]]
    np.testing.assert_allclose(rec.time, -1e-3 + (k[rises] - 0.5) * 1e-5, atol=1e-9)


def test_waveform_indices_written_as_floats_read_as_integers_do(tmp_path, monkeypatch):
    """The Sequence indices are parsed as integers when they are; chunks whose indices are written
    otherwise (``1500.0``, ``1.5e3``) fall back to floats and give the same edges and lines."""
    from motorlab.io import _chunks

    monkeypatch.setattr(_chunks, "CHUNK", 2048)
    k = np.arange(3000)
    volts = np.where((k // 50) % 2 == 1, 3.3, 0.0)
    plain, mixed = tmp_path / "plain.csv", tmp_path / "mixed.csv"
    _square_wave_export(plain, rows=[f"{i},{v:.4e}," for i, v in zip(k, volts, strict=True)])
    _square_wave_export(mixed, rows=[(f"{i}.0" if 1200 <= i < 1800 else f"{i:.4e}" if i >= 2500 else f"{i}") +
                                     f",{v:.4e}," for i, v in zip(k, volts, strict=True)])
    a, b = read_scope_waveform(plain), read_scope_waveform(mixed)
    np.testing.assert_array_equal(a.time, b.time)
    np.testing.assert_array_equal(a.lines, b.lines)
    assert a.time.size == 30


def test_waveform_errors_name_the_line_in_any_chunk(tmp_path, monkeypatch):
    from motorlab.io import _chunks

    monkeypatch.setattr(_chunks, "CHUNK", 256)
    rows = [f"{i},{(i // 50) % 2 * 3.3:.4e}," for i in range(2000)]
    rows[1500] = "1500,nan,"
    path = tmp_path / "w.csv"
    _square_wave_export(path, rows=rows)
    with pytest.raises(LogFormatError, match=r"w\.csv:1503: CH1: 'nan' is not a finite number"):
        read_scope_waveform(path)
    rows[1500] = "1499,0,"
    _square_wave_export(path, rows=rows)
    with pytest.raises(LogFormatError, match=r"w\.csv:1503: sample times must increase"):
        read_scope_waveform(path)


def test_waveform_with_bare_carriage_returns_is_read_whole(tmp_path):
    path = tmp_path / "w.csv"
    _square_wave_export(path, newline="\r", end="\r")
    rec = read_scope_waveform(path)
    assert rec.time.size == 30
    assert rec.time[0] == pytest.approx(-1e-3 + 49.5e-5, abs=1e-7)  # the 10 mV ripple moves it 0.02 µs


def test_reading_a_waveform_reports_progress(tmp_path, monkeypatch):
    from motorlab import progress
    from motorlab.io import _chunks

    monkeypatch.setattr(_chunks, "CHUNK", 4096)
    path = tmp_path / "capture.csv"
    _square_wave_export(path, n=20000)
    seen: list[progress.Progress] = []
    with progress.reporting(seen.append):
        read_scope_waveform(path)
    reading = [p for p in seen if p.what == "Reading capture.csv"]
    assert reading[0].unit == "MB"
    assert reading[0].total == pytest.approx(path.stat().st_size / 1e6, abs=0.05)
    assert len(reading) > 20  # one report a chunk
    assert all(b.done >= a.done for a, b in itertools.pairwise(reading))
    assert reading[-1].finished
    assert any(p.what.startswith("Finding the edges") and p.finished for p in seen)
