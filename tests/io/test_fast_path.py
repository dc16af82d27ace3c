"""The C fast path of the table readers gives exactly what the line-by-line path gives."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from motorlab.estimation.decimate import block_mean
from motorlab.io import text as _text
from motorlab.io.text import fast_table, text_file
from motorlab.recording import Recording

VALUE = st.one_of(st.integers(-(10**9), 10**9).map(str),
                  st.floats(-1e12, 1e12, allow_nan=False).map(lambda x: f"{x:.6g}"))


@settings(max_examples=60, deadline=None)
@given(rows=st.lists(st.lists(VALUE, min_size=3, max_size=3), min_size=1, max_size=40),
       delimiter=st.sampled_from([",", " ", "\t", ";"]), blank_every=st.integers(0, 7),
       crlf=st.booleans(), final_newline=st.booleans(), chunk=st.sampled_from([5, 64, 1 << 21]))
def test_fast_table_equals_the_rows_as_written(rows, delimiter, blank_every, crlf, final_newline, chunk) -> None:
    lines, numbers = ["a b c"], []
    for k, row in enumerate(rows):
        if blank_every and k % blank_every == 0:
            lines.append("")
        lines.append(delimiter.join(row))
        numbers.append((len(lines), [float(v) for v in row]))
    end = "\r\n" if crlf else "\n"
    raw = (end.join(lines) + (end if final_newline else "")).encode()
    old, _text._CHUNK = _text._CHUNK, chunk
    try:
        table = fast_table(text_file("t.txt", raw), 2, 3, None if delimiter == " " else delimiter)
    finally:
        _text._CHUNK = old
    assert table is not None
    assert table.truncated is None
    assert table.lines.tolist() == [n for n, _ in numbers]
    np.testing.assert_array_equal(table.values, np.array([v for _, v in numbers]))


def test_fast_table_leaves_irregular_rows_to_the_slow_path() -> None:
    for body in (b"1 2 3\n4 nan 6\n", b"1 2 3\n4 5\n7 8 9\n", b"1 2 3\n# note\n4 5 6\n", b"1 2 3\n4 0x10 6\n",
                 b"1 2 3\n4 1_0 6\n", b"1 2 3\n4 1e 6\n", b"1 2 3\r4 5 6\r"):
        assert fast_table(text_file("t.txt", b"a b c\n" + body), 2, 3, None) is None, body


def test_fast_table_drops_a_truncated_last_line() -> None:
    table = fast_table(text_file("t.csv", b"a,b\n1,2\n3,4\n5,"), 2, 2, ",")
    assert table is not None
    assert table.truncated == (4, "5,")
    assert table.values.tolist() == [[1, 2], [3, 4]]


def test_block_mean_averages_long_logs_and_says_so() -> None:
    n = 10_007
    t = np.arange(n) * 1e-3
    rec = Recording(time=t, signals={"counts": np.arange(n, dtype=float)}, source="log.txt",
                    lines=np.arange(n) + 3, metadata={"warnings": ["earlier"]})
    assert block_mean(rec, max_points=n) is rec
    out = block_mean(rec, max_points=1000)
    assert len(out) == 910  # blocks of 11, the last one shorter
    assert out.time[0] == np.mean(t[:11])
    assert out.signals["counts"][-1] == np.mean(np.arange(909 * 11, n))
    assert out.lines[:2].tolist() == [3, 14]
    assert out.metadata["decimation"] == {"block": 11, "samples": n, "points": 910}
    assert out.metadata["warnings"][0] == "earlier"
    assert "averaged in blocks of 11" in out.metadata["warnings"][1]
