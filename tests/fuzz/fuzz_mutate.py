"""Hand-written mutators: what a user's files, options and session files can do to motorlab.

Every mutator takes a :class:`Chooser` (a seeded ``random.Random`` in the long run, hypothesis's
``data.draw`` in ``make test``, so that a failure shrinks) and returns the mutated bytes, or the
mutated option list. The mutation's name is kept with the case: a failure file says what was done.
"""

from __future__ import annotations

import json
import random
import re
from collections.abc import Callable, Sequence
from typing import Any, Protocol, TypeVar

T = TypeVar("T")


class Chooser(Protocol):
    """The source of every choice of a case (random or hypothesis)."""

    def choice(self, options: Sequence[T]) -> T: ...

    def integer(self, low: int, high: int) -> int: ...


class RandomChooser:
    """Choices from a seeded :class:`random.Random`: case ``k`` of seed ``s`` is always the same."""

    def __init__(self, seed: str | int):
        self.rng = random.Random(seed)

    def choice(self, options: Sequence[T]) -> T:
        return options[self.rng.randrange(len(options))]

    def integer(self, low: int, high: int) -> int:
        return self.rng.randint(low, high)


#: Numbers no instrument writes, as text: non-finite, beyond a float, sub-normal, huge integers,
#: expressions, hexadecimal, digit separators, sensor glitches.
HOSTILE_NUMBERS = (
    "nan", "NaN", "inf", "-inf", "Infinity", "1e308", "-1e308", "1e309", "1e-300", "-1e-300", "5e-324", "0", "-0",
    "65535", "2147483647", "-2147483648", "4294967295", "9" * 5000, "1" + "0" * 400, "1e", "+-1", "1_0", "0x10",
    "", " ", "abc", "1.2.3", "--1", "1e99999", "9**9**9", "2**1024", "(1)", "1e-12", "-1",
)

#: Values an option may be given: the numbers above with and without units, and option-ish words.
HOSTILE_OPTION_VALUES = (
    *HOSTILE_NUMBERS, "9**9**9 kg*m^2", "2**1024 V", "9**9**9 m", "1e-12", "1e12", "3 furlongs", "0.5 A", "12 V",
    "1 kg", "400 in*oz", "((((((1))))))", "m^999", "1/0", "0/0", "-", "--", "-h", "\x00", "é", "1e308 A",
    "/dev/zero", ".", "..", "/", "99999999999999999999999999999999999999999", "1" * 300,
)

#: What a JSON value can be replaced by: every type, huge and odd numbers, deep nesting.
JSON_VALUES: tuple[Any, ...] = (
    None, True, False, 0, -1, 1.5, "text", "", [], {}, [None], [[1, 2], [3]], {"a": 1}, float("nan"), float("inf"),
    -float("inf"), 1e308, 5e-324, 2**63, -(2**63), 10**400, "1e5", [1.0] * 3, "NaN",
)


# ---- bytes -------------------------------------------------------------------------------------


def truncate(raw: bytes, c: Chooser) -> bytes:
    return raw[: c.integer(0, max(0, len(raw) - 1))]


def flip_bytes(raw: bytes, c: Chooser) -> bytes:
    data = bytearray(raw)
    for _ in range(c.integer(1, 8)):
        if data:
            data[c.integer(0, len(data) - 1)] = c.integer(0, 255)
    return bytes(data)


def insert_bytes(raw: bytes, c: Chooser) -> bytes:
    at = c.integer(0, len(raw))
    junk = c.choice([b"\x00", b"\xff\xfe", b"\xef\xbb\xbf", b"\r", b"\n\n\n", b"\xc3\xa9", b"\xb5", b"\x1a",
                     b"#", b",", b";", b"\t", b"{", b"[", b"]", b"}", b'"', b"\\", b"9" * 5000])
    return raw[:at] + junk + raw[at:]


def delete_range(raw: bytes, c: Chooser) -> bytes:
    a = c.integer(0, max(0, len(raw) - 1))
    b = c.integer(a, min(len(raw), a + c.choice([1, 16, 256, 4096])))
    return raw[:a] + raw[b:]


def duplicate_range(raw: bytes, c: Chooser) -> bytes:
    a = c.integer(0, max(0, len(raw) - 1))
    b = c.integer(a, min(len(raw), a + c.choice([1, 64, 1024])))
    return raw[:b] + raw[a:b] * c.choice([1, 2, 50]) + raw[b:]


def reencode(raw: bytes, c: Chooser) -> bytes:
    kind = c.choice(["utf-16", "bom", "crlf", "cr", "latin-1", "nul-end", "empty", "spaces", "no-final-newline"])
    text = raw.decode("utf-8", "replace")
    if kind == "utf-16":
        return text.encode("utf-16")
    if kind == "bom":
        return b"\xef\xbb\xbf" + raw
    if kind == "crlf":
        return raw.replace(b"\n", b"\r\n")
    if kind == "cr":
        return raw.replace(b"\n", b"\r")
    if kind == "latin-1":
        return text.replace("m", "µ", 1).encode("latin-1", "replace")
    if kind == "nul-end":
        return raw + b"\x00" * c.choice([1, 100])
    if kind == "empty":
        return b""
    if kind == "spaces":
        return b" \n\t\n" * c.choice([1, 1000])
    return raw.rstrip(b"\r\n")


BYTE_MUTATORS: dict[str, Callable[[bytes, Chooser], bytes]] = {
    "truncate": truncate, "flip-bytes": flip_bytes, "insert-bytes": insert_bytes, "delete-range": delete_range,
    "duplicate-range": duplicate_range, "reencode": reencode,
}


# ---- text tables -------------------------------------------------------------------------------

_NUMBER = re.compile(rb"(?<![\w.])[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?(?![\w.])")


def replace_number(raw: bytes, c: Chooser) -> bytes:
    """One or a few numbers of the file replaced by hostile ones (a glitch, NaN, 1e308, a huge integer)."""
    matches = list(_NUMBER.finditer(raw[:2_000_000]))
    if not matches:
        return raw
    chosen = {c.integer(0, len(matches) - 1) for _ in range(c.choice([1, 1, 3]))}
    out = raw
    for k in sorted(chosen, reverse=True):  # from the end: earlier offsets stay valid
        m = matches[k]
        out = out[: m.start()] + c.choice(HOSTILE_NUMBERS).encode() + out[m.end():]
    return out


def _lines(raw: bytes) -> list[bytes]:
    return raw.split(b"\n")


def repeat_line(raw: bytes, c: Chooser) -> bytes:
    """A row repeated (identical timestamps), possibly many times."""
    lines = _lines(raw)
    k = c.integer(0, len(lines) - 1)
    return b"\n".join(lines[:k] + [lines[k]] * c.choice([2, 3, 100]) + lines[k + 1 :])


def reverse_lines(raw: bytes, c: Chooser) -> bytes:
    """A stretch of rows reversed (time running backwards) or the whole file."""
    lines = _lines(raw)
    a = c.integer(0, len(lines) - 1)
    b = c.choice([len(lines), min(len(lines), a + c.choice([2, 10, 100]))])
    return b"\n".join(lines[:a] + lines[a:b][::-1] + lines[b:])


def drop_lines(raw: bytes, c: Chooser) -> bytes:
    """The header, the first rows, or all rows but a few."""
    lines = _lines(raw)
    kind = c.choice(["head", "rows", "keep-few"])
    if kind == "head":
        return b"\n".join(lines[c.choice([1, 2, 5]) :])
    if kind == "rows":
        a = c.integer(0, len(lines) - 1)
        return b"\n".join(lines[:a] + lines[a + c.choice([1, 10, 1000]) :])
    return b"\n".join(lines[: c.choice([1, 2, 3, 4])])


def constant_column(raw: bytes, c: Chooser) -> bytes:
    """Every number of one column the same (an unplugged sensor) or every row identical."""
    lines = _lines(raw)
    body = [k for k, line in enumerate(lines) if line[:1].strip(b" \t").isdigit() or line[:1] == b"-"]
    if len(body) < 2:
        return raw
    first = lines[body[0]]
    for k in body[1:]:
        lines[k] = first
    return b"\n".join(lines)


TEXT_MUTATORS: dict[str, Callable[[bytes, Chooser], bytes]] = {
    "replace-number": replace_number, "repeat-line": repeat_line, "reverse-lines": reverse_lines,
    "drop-lines": drop_lines, "constant-column": constant_column,
}


# ---- JSON -------------------------------------------------------------------------------------


def _paths(node: Any, prefix: tuple[Any, ...] = (), limit: int = 400) -> list[tuple[Any, ...]]:
    """Paths to nodes of a JSON document (lists sampled: their first, middle and last items)."""
    out = [prefix]
    if len(prefix) > 8:
        return out
    if isinstance(node, dict):
        for key, value in list(node.items())[:50]:
            out += _paths(value, (*prefix, key), limit)
    elif isinstance(node, list) and node:
        for k in sorted({0, len(node) // 2, len(node) - 1}):
            out += _paths(node[k], (*prefix, k), limit)
    return out[:limit]


def _dumps(doc: Any) -> bytes:
    text = json.dumps(doc, allow_nan=True)
    return text.encode()


def json_value(raw: bytes, c: Chooser) -> bytes:
    """A node of the document replaced by a value of another type, a huge or non-finite number, or removed."""
    try:
        doc = json.loads(raw)
    except (ValueError, RecursionError):
        return flip_bytes(raw, c)
    paths = _paths(doc)
    path = c.choice(paths[1:] or paths)
    if not path:
        return _dumps(c.choice(JSON_VALUES))
    parent = doc
    for key in path[:-1]:
        parent = parent[key]
    action = c.choice(["replace", "replace", "delete", "nest", "huge-list"])
    if action == "delete":
        del parent[path[-1]]
    elif action == "nest":
        depth = c.choice([50, 1000, 100_000])
        parent[path[-1]] = json.loads("[" * min(depth, 900) + "]" * min(depth, 900)) if depth < 1000 else None
        if depth >= 1000:  # deeper than json.dumps can write: splice the text
            text = _dumps(doc).replace(b"null", b"[" * depth + b"]" * depth, 1)
            return text
    elif action == "huge-list":
        parent[path[-1]] = [c.choice(JSON_VALUES[:12])] * c.choice([0, 1, 10_000])
    else:
        parent[path[-1]] = c.choice(JSON_VALUES)
    return _dumps(doc)


def json_numbers(raw: bytes, c: Chooser) -> bytes:
    """Numbers of a JSON file written as literals no float holds (5,000 digits, 1e999) or as NaN."""
    matches = list(_NUMBER.finditer(raw[:2_000_000]))
    if not matches:
        return raw
    m = c.choice(matches)
    value = c.choice([b"9" * 5000, b"1" + b"0" * 400, b"1e999", b"-1e999", b"NaN", b"Infinity", b"-Infinity",
                      b"1e-400", b"0", b"-0.0", b"2147483647", b"9" * 4300])
    return raw[: m.start()] + value + raw[m.end():]


JSON_MUTATORS: dict[str, Callable[[bytes, Chooser], bytes]] = {"json-value": json_value, "json-numbers": json_numbers}


# ---- TOML (session files) ---------------------------------------------------------------------

_TOML_VALUE = re.compile(rb'^(\s*[\w.]+\s*=\s*)(.+)$', re.MULTILINE)


def toml_value(raw: bytes, c: Chooser) -> bytes:
    """A value of the session replaced: hostile quantities, wrong types, paths to special files, huge integers."""
    matches = list(_TOML_VALUE.finditer(raw))
    if not matches:
        return raw
    m = c.choice(matches)
    value = c.choice([
        '"9**9**9 m"', '"2**1024 m"', '"1e308 m"', '"-0.15 m"', '"0 m"', '"nan m"', '"15 furlongs"', "nan", "inf",
        "9" * 5000, "1" + "0" * 400, "-1", "0", "true", "[]", "{}", '""', '"."', '["."]', '["/dev/zero"]',
        '["fifo.csv"]', '["loop.csv"]', '["missing.csv"]', '["lcr.csv", "lcr.csv"]', '["../../../etc/passwd"]',
        '["' + "a" * 5000 + '"]', '"neverest40"', '"nonsense"', "1e999", '"\\u0000"', "[" * 1000 + "]" * 1000,
    ])
    return raw[: m.start(2)] + value.encode() + raw[m.end(2):]


def toml_structure(raw: bytes, c: Chooser) -> bytes:
    """The session's structure broken: tables nested 1,000 deep, keys repeated, unknown keys, a unit removed."""
    kind = c.choice(["deep-table", "deep-inline", "repeat-key", "unknown-key", "no-units", "many-units"])
    if kind == "deep-table":
        return raw + b"\n[" + b".".join([b"x"] * c.choice([100, 1000, 5000])) + b"]\ny = 1\n"
    if kind == "deep-inline":
        depth = c.choice([100, 1000])
        return raw + b"\nnest = " + b"{a = " * depth + b"1" + b"}" * depth + b"\n"
    if kind == "repeat-key":
        return raw + b"\n[motor]\ncatalog = \"neverest40\"\n"
    if kind == "unknown-key":
        return raw.replace(b"[rig]\n", b"[rig]\nlever_arms = \"0.15 m\"\n")
    if kind == "no-units":
        return raw.split(b"[units")[0]
    extra = b"".join(b'[units.U%d.lcr]\nfiles = ["lcr.csv"]\n' % k for k in range(c.choice([20, 200])))
    return raw + b"\n" + extra


TOML_MUTATORS: dict[str, Callable[[bytes, Chooser], bytes]] = {
    "toml-value": toml_value, "toml-structure": toml_structure,
}


def mutators_for(kind: str) -> dict[str, Callable[[bytes, Chooser], bytes]]:
    """The mutators that suit a file kind (``text``, ``json``, ``toml``, ``binary``)."""
    table = dict(BYTE_MUTATORS)
    if kind in ("text", "json", "toml"):
        table.update(TEXT_MUTATORS)
    if kind != "text":
        table.pop("constant-column", None)  # rows of numbers: a text table's
    if kind == "json":
        table.update(JSON_MUTATORS)
        table.update({"json-value-2": json_value})  # structure-aware mutations weigh more
    if kind == "toml":
        table.update(TOML_MUTATORS)
        table.update({"toml-value-2": toml_value})
    return table


#: What an input path can be made to be instead of a file.
SPECIAL_FILES = ("directory", "fifo", "dev-zero", "symlink-loop", "missing", "symlink-to-file", "empty",
                 "unreadable", "huge-sparse")


def mutate_options(options: list[str], known: Sequence[str], c: Chooser) -> tuple[list[str], str]:
    """Options with a value replaced, an option added with a hostile value, or the option list shuffled."""
    opts = list(options)
    kind = c.choice(["replace", "add", "add", "repeat", "empty-output"])
    values = [k for k in range(len(opts)) if not opts[k].startswith("-") and k > 0 and opts[k - 1].startswith("--")]
    if kind == "replace" and values:
        k = c.choice(values)
        opts[k] = c.choice(HOSTILE_OPTION_VALUES)
        return opts, f"option {opts[k - 1]}={opts[k]!r}"
    if kind in ("add", "replace") and known:
        name = c.choice(list(known))
        value = c.choice(HOSTILE_OPTION_VALUES)
        return [*opts, f"{name}={value}"], f"option {name}={value!r}"
    if kind == "repeat" and values:
        k = c.choice(values)
        return [*opts, opts[k - 1], c.choice(HOSTILE_OPTION_VALUES)], f"option {opts[k - 1]} given twice"
    target = c.choice(["-o", "--plot"])
    return [*opts, target, c.choice(["", " ", ".", "/", "/dev/null", "x.exe", "missing/x.png", "fifo.csv"])], (
        f"output {target}")
