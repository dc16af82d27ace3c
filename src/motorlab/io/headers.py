"""Column headers in words: ``Current (A)``, ``Torque 6V (N · m)``, ``Speed (RPM)``, ``Amps`` — and ``--column``.

Dynamometers, data loggers and spreadsheets name a column by its quantity in words, with its unit in
brackets or parentheses (VEX Robotics' motor dynamometer: ``Time,Amps,Volts,Torque 6V (N · m)``,
``Speed (RPM),Torque (N·m),Current (A),Supplied Power (W),…``). :func:`worded_column` recognises
such a header by its quantity word (:data:`QUANTITY_WORDS`) and its unit (pint, :mod:`motorlab.units`);
anything else is mapped by the person: ``--column "HEADER=quantity"`` on the command line, a
``columns`` table in the session file, ``columns={"HEADER": "quantity"}`` in the notebook
(:func:`parse_column_mapping`). The mapping in force while a file is read is a context variable
(:func:`column_mapping`), so that every reader of a headed CSV honours it without each analysis
passing it on.

A target is a quantity word (``current``; the unit then comes from the header's brackets, else the
quantity's SI unit), a quantity with its unit (``current [mA]``), one of the CSV format's own column
names (``current_mA``), or ``skip`` (the column is not read).
"""

from __future__ import annotations

import contextlib
import contextvars
import re
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from motorlab.errors import LogFormatError, OptionError

#: Known column names -> (canonical signal, unit as written). ``"time"`` is the time axis [s].
COLUMNS: dict[str, tuple[str, str]] = {
    "time_s": ("time", "s"),
    "time_ms": ("time", "ms"),
    "voltage_V": ("voltage", "V"),
    "current_A": ("current", "A"),
    "current_mA": ("current", "mA"),
    "position_counts": ("counts", "count"),
    "position_rad": ("position", "rad"),
    "position_rev": ("position", "revolution"),
    "velocity_rad_per_s": ("velocity", "rad/s"),
    "velocity_rpm": ("velocity", "rpm"),
    "command_V": ("command", "V"),
    "mass_kg": ("mass", "kg"),
    "mass_g": ("mass", "g"),
    "torque_Nm": ("torque", "N*m"),
    "L_uH": ("inductance", "uH"),
    "L_mH": ("inductance", "mH"),
    "L_H": ("inductance", "H"),
    "Q": ("quality_factor", "dimensionless"),
    "DCR_ohm": ("dc_resistance", "ohm"),
    "frequency_Hz": ("frequency", "Hz"),
    "speed_rpm": ("speed", "rpm"),
    "speed_rad_per_s": ("speed", "rad/s"),
    "tach_voltage_V": ("tach_voltage", "V"),
    "battery_V": ("battery", "V"),
    "winding_temperature_C": ("winding_temperature", "degC"),  # motorlab simulate stall's forecast
    "case_temperature_C": ("case_temperature", "degC"),
}

_BY_LOWER = {name.lower(): name for name in COLUMNS}


def column_name(name: str) -> str | None:
    """The known column ``name`` refers to (case-insensitive), or None."""
    return _BY_LOWER.get(name.strip().lower())


#: Quantity -> (signal name of :data:`motorlab.recording.SIGNALS` or ``"time"``, SI unit).
QUANTITIES: dict[str, tuple[str, str]] = {
    "time": ("time", "s"),
    "voltage": ("voltage", "V"),
    "current": ("current", "A"),
    "torque": ("torque", "N*m"),
    "speed": ("speed", "rad/s"),
    "velocity": ("velocity", "rad/s"),
    "position": ("position", "rad"),
    "counts": ("counts", "count"),
    "output_power": ("output_power", "W"),
    "input_power": ("input_power", "W"),
    "power_dissipation": ("power_dissipation", "W"),
    "efficiency": ("efficiency", "1"),
    "temperature": ("temperature", "K"),
    "mass": ("mass", "kg"),
    "command": ("command", "V"),
    "battery": ("battery", "V"),
    "frequency": ("frequency", "Hz"),
    "inductance": ("inductance", "H"),
    "dc_resistance": ("dc_resistance", "ohm"),
}

#: A word of a header -> (quantity, the unit the word itself is, if it is one).
QUANTITY_WORDS: dict[str, tuple[str, str | None]] = {
    "time": ("time", None), "t": ("time", None), "elapsed": ("time", None), "timestamp": ("time", None),
    "seconds": ("time", "s"), "sec": ("time", "s"),
    "voltage": ("voltage", None), "volts": ("voltage", "V"), "volt": ("voltage", "V"), "v": ("voltage", "V"),
    "current": ("current", None), "amps": ("current", "A"), "amp": ("current", "A"),
    "amperes": ("current", "A"), "ampere": ("current", "A"), "i": ("current", None),
    "torque": ("torque", None),
    "speed": ("speed", None), "rpm": ("speed", "rpm"),
    "velocity": ("velocity", None),
    "position": ("position", None), "angle": ("position", None),
    "counts": ("counts", "count"), "ticks": ("counts", "count"),
    "efficiency": ("efficiency", None),
    "temperature": ("temperature", None), "temp": ("temperature", None),
    "mass": ("mass", None), "weight": ("mass", None),
    "battery": ("battery", None), "frequency": ("frequency", None), "inductance": ("inductance", None),
}

#: Words that say which power a ``Power`` column holds.
_POWER_KINDS: dict[str, str] = {
    "output": "output_power", "out": "output_power", "mechanical": "output_power", "shaft": "output_power",
    "supplied": "input_power", "supply": "input_power", "input": "input_power", "in": "input_power",
    "electrical": "input_power",
    "dissipation": "power_dissipation", "dissipated": "power_dissipation", "loss": "power_dissipation",
    "losses": "power_dissipation", "heat": "power_dissipation", "lost": "power_dissipation",
    "wasted": "power_dissipation",
}

#: Targets that leave a column out.
SKIP = ("skip", "ignore")

_BRACKETED = re.compile(r"^(?P<words>.*?)\s*(?:\((?P<p>[^()]*)\)|\[(?P<b>[^\[\]]*)\])\s*$")
_WORD = re.compile(r"[a-z]+[0-9]*|[0-9][0-9.]*[a-z]*")
_TOKEN_UNIT = {
    "rpm": "rpm", "%": "percent", "°c": "degC", "ºc": "degC", "degc": "degC", "c": "degC", "°f": "degF",
    "f": "degF", "k": "kelvin", "n.m": "N*m", "n-m": "N*m", "oz-in": "ozf*in", "oz.in": "ozf*in",
    "in-oz": "ozf*in", "in-lb": "lbf*in", "ft-lb": "lbf*ft", "rad/s": "rad/s", "1": "dimensionless",
    "amps": "A", "amp": "A", "amperes": "A", "ampere": "A", "a": "A", "ma": "mA", "milliamps": "mA",
    "volts": "V", "volt": "V", "v": "V", "mv": "mV",
    "in-lbs": "lbf*in", "lb-in": "lbf*in", "lbs-in": "lbf*in", "ft-lbs": "lbf*ft", "lb-ft": "lbf*ft",
    "rev/min": "rpm", "r/min": "rpm", "rev/s": "revolution/s", "rps": "revolution/s", "r/s": "revolution/s",
}
#: Masses that stand for weights in a torque unit (oz·in, kg·cm on gearmotor sheets): their force units.
_WEIGHTS = re.compile(r"\b(oz|lb|kg|g)\b")

Target = tuple[str, str]  # (signal or "time", unit as written)


@dataclass(frozen=True)
class ColumnRule:
    """One ``HEADER=target`` rule: the header as given, the quantity, and the unit given with it (or None)."""

    header: str
    quantity: str | None  # None: skip the column
    unit: str | None = None

    def text(self) -> str:
        """The rule as the CLI writes it."""
        target = "skip" if self.quantity is None else self.quantity + (f" [{self.unit}]" if self.unit else "")
        return f"{self.header}={target}"


_MAPPING: contextvars.ContextVar[tuple[ColumnRule, ...]] = contextvars.ContextVar("motorlab_columns", default=())


def current_mapping() -> tuple[ColumnRule, ...]:
    """The column rules in force (:func:`column_mapping`); empty when none were given."""
    return _MAPPING.get()


@contextlib.contextmanager
def column_mapping(rules: Any) -> Iterator[tuple[ColumnRule, ...]]:
    """Read headed CSV files with these column rules while the block runs.

    ``rules``: what :func:`parse_column_mapping` takes (None or empty: no rules, the ones in force kept).
    """
    parsed = parse_column_mapping(rules)
    token = _MAPPING.set(parsed or _MAPPING.get())
    try:
        yield parsed
    finally:
        _MAPPING.reset(token)


def parse_column_mapping(value: Any, *, name: str = "--column") -> tuple[ColumnRule, ...]:
    """Column rules from ``"HEADER=quantity"`` strings, a list of them, a mapping header -> target, or rules.

    Raises
    ------
    OptionError
        A rule without ``=``, an empty header, an unknown quantity or unit (naming the rule and the
        quantities known).
    """
    if value is None:
        return ()
    if isinstance(value, ColumnRule):
        return (value,)
    if isinstance(value, str):
        return (_parse_rule(value, name),)
    if isinstance(value, Mapping):
        return tuple(_rule(str(header), target, name) for header, target in value.items())
    if isinstance(value, Sequence):
        out: list[ColumnRule] = []
        for item in value:
            out.extend(parse_column_mapping(item, name=name))
        headers = [rule.header.casefold() for rule in out]
        twice = next((r.header for k, r in enumerate(out) if headers[k] in headers[:k]), None)
        if twice is not None:
            raise OptionError(f"{name}: the column {twice!r} is mapped twice")
        return tuple(out)
    raise OptionError(f"{name}: expected \"HEADER=quantity\" text, got {value!r}")


def _parse_rule(text: str, name: str) -> ColumnRule:
    header, sep, target = text.rpartition("=")
    if not sep:
        raise OptionError(f"{name} {text!r}: write HEADER=quantity, e.g. --column \"Amps=current\"")
    return _rule(header, target, name)


def _rule(header: str, target: Any, name: str) -> ColumnRule:
    header = header.strip().strip('"')
    if not header:
        raise OptionError(f"{name}: the column header before '=' is empty")
    if not isinstance(target, str):
        raise OptionError(f"{name} {header!r}: the target must be text such as \"current\", got {target!r}")
    text = target.strip()
    if text.lower() in SKIP:
        return ColumnRule(header, None)
    known = column_name(text)
    if known is not None:  # current_mA
        signal, column_unit = COLUMNS[known]
        quantity = next((q for q, (s, _u) in QUANTITIES.items() if s == signal), signal)
        return ColumnRule(header, quantity, column_unit)
    match = _BRACKETED.match(text)
    unit: str | None
    words, unit = (match.group("words"), match.group("p") or match.group("b")) if match else (text, None)
    quantity = words.strip().lower().replace(" ", "_").replace("-", "_")
    if quantity not in QUANTITIES and quantity in QUANTITY_WORDS:  # "amps", "volts", "rpm"
        quantity, word_unit = QUANTITY_WORDS[quantity]
        unit = unit or word_unit
    if quantity not in QUANTITIES:
        raise OptionError(
            f"{name} \"{header}={text}\": unknown quantity {words.strip()!r}; known: {', '.join(QUANTITIES)}, skip"
        )
    if unit is not None:
        unit = _check_unit(unit, quantity, lambda message: OptionError(f"{name} \"{header}={text}\": {message}"))
    return ColumnRule(header, quantity, unit)


# ---- recognising a header ----------------------------------------------------------------------


def normalise_unit(text: str) -> str:
    """A unit as dynamometers write it (``N · m``, ``N·m``, ``RPM``, ``°C``, ``%``) as pint reads it."""
    unit = text.strip()
    nm = re.fullmatch(r"([munk]?)N[mM]", unit)  # Nm, mNm (not nm, a nanometre)
    if nm:
        return f"{nm.group(1)}N*m"
    low = unit.lower().replace(" ", "")
    if low in _TOKEN_UNIT:
        return _TOKEN_UNIT[low]
    unit = re.sub(r"\s*[·⋅•∙×]\s*|\s*\.\s*(?=[A-Za-z])", "*", unit)  # N · m, N·m, N.m
    unit = re.sub(r"\blbs\b", "lb", unit)
    unit = unit.replace("Ω", "ohm").replace("µ", "u").replace("μ", "u").replace("²", "^2").replace("°", "deg")
    unit = re.sub(r"(?<=[A-Za-z])(\s+|-)(?=[A-Za-z])", "*", unit)  # "N m", "kgf-cm"
    return unit


def _check_unit(text: str, quantity: str, error: Any) -> str:
    """``text`` as a pint unit of ``quantity``'s dimension, or ``error(message)`` raised."""
    from motorlab.units import registry

    si = QUANTITIES[quantity][1]
    unit = normalise_unit(text)
    ureg = registry()
    try:
        parsed = ureg.Unit(unit)
    except Exception:  # pint raises several types for text that is no unit
        try:
            parsed = ureg.Unit(unit.lower())
            unit = unit.lower()
        except Exception:
            raise error(f"unknown unit {text.strip()!r}") from None
    if quantity == "torque" and parsed.dimensionality == ureg.Unit("kg*m").dimensionality:
        unit = _WEIGHTS.sub(r"\1f", unit)  # oz·in, kg·cm: a weight on an arm, as the sheets mean it
        parsed = ureg.Unit(unit)
    if parsed.dimensionality != ureg.Unit(si).dimensionality:
        raise error(f"{text.strip()!r} is not a unit of {quantity.replace('_', ' ')} (SI: {si})")
    return unit


#: Quantities whose unit is never guessed when a header gives none (a "Speed" column may be rpm or rad/s).
_NO_DEFAULT_UNIT = ("speed", "velocity", "position")


def worded_column(field: str) -> tuple[str, str | None] | None:
    """The quantity and the unit (as pint reads it, or None) of a header in words, or None if it names none.

    ``"Torque 6V (N · m)"`` -> ``("torque", "N*m")``; ``"Amps"`` -> ``("current", "A")``;
    ``"Power Output (W)"`` -> ``("output_power", "W")``; ``"Time"`` -> ``("time", None)``.

    Raises
    ------
    LogFormatError
        (without a path: the caller adds it) when the words name a quantity but the unit is not one of
        it, or when they name two quantities.
    """
    match = _BRACKETED.match(field)
    words, unit_text = (match.group("words"), match.group("p") or match.group("b")) if match else (field, None)
    if unit_text is None and "_" in field.strip():  # name_unit, as this format's own columns: temperature_C
        words, _sep, unit_text = field.strip().rpartition("_")
        words = words.replace("_", " ")
    tokens = _WORD.findall(words.lower())
    found: list[tuple[str, str | None]] = []
    if "power" in tokens:
        kinds = {_POWER_KINDS[t] for t in tokens if t in _POWER_KINDS} or {"output_power"}  # a datasheet's "Power"
        if len(kinds) != 1:
            return None  # "Input Output Power": which? the person says, with --column
        found.append((kinds.pop(), None))
    else:
        for token in tokens:
            if token in QUANTITY_WORDS and QUANTITY_WORDS[token] not in found:
                found.append(QUANTITY_WORDS[token])
    if len({q for q, _u in found}) != 1:
        return None  # no quantity word, or two: "Voltage Current" is no header to guess at
    quantity, word_unit = found[0]
    if unit_text is None and word_unit is None and quantity in _NO_DEFAULT_UNIT:
        raise LogFormatError(f"column {field!r} names a {quantity} without a unit (rpm? rad/s?: both are in use)")
    if unit_text is None:
        return quantity, word_unit
    unit = _check_unit(unit_text, quantity, lambda message: LogFormatError(f"column {field!r}: {message}"))
    return quantity, unit


def resolve_column(field: str, rules: Sequence[ColumnRule]) -> Target | str | None:
    """What a header field is read as: (signal, unit as pint reads it), None (skip), or ``"unknown"``.

    A rule for the field (the header as written, compared without regard to case and surrounding
    spaces) comes first; then a header in words with a unit in brackets.
    """
    key = field.strip().casefold()
    for rule in rules:
        if rule.header.casefold() == key:
            if rule.quantity is None:
                return None
            signal, si = QUANTITIES[rule.quantity]
            unit = rule.unit
            if unit is None:
                unit = _bracketed_unit(field, rule.quantity) or si
            return signal, unit
    worded = worded_column(field)
    if worded is None:
        return "unknown"
    quantity, unit = worded
    signal, si = QUANTITIES[quantity]
    return signal, unit or si


def _bracketed_unit(field: str, quantity: str) -> str | None:
    """The unit in the brackets of ``field`` when it is one of ``quantity`` (``Load (mA)`` for current), else None."""
    match = _BRACKETED.match(field)
    unit = match and (match.group("p") or match.group("b"))
    if not unit:
        return None
    try:
        return _check_unit(unit, quantity, LogFormatError)
    except LogFormatError:
        return None


def unknown_column_message(field: str, rules: Sequence[ColumnRule]) -> str:
    """The one-line refusal of a header that cannot be read, with the ``--column`` form that maps it."""
    shown = field if field else "(empty)"
    unused = [rule.text() for rule in rules if rule.header.casefold() != field.strip().casefold()]
    hint = field.strip() or "HEADER"
    text = (f"column {shown!r} names no quantity motorlab knows: map it with --column \"{hint}=QUANTITY\" "
            f"(QUANTITY one of {', '.join(QUANTITIES)}, optionally with a unit: \"{hint}=current [mA]\"; "
            f"or \"{hint}=skip\"; in a session file: columns = {{ \"{hint}\" = \"QUANTITY\" }}), or name it like "
            "time_s, current_A (docs/formats.md)")
    if rules:
        text += f"; the mapping given ({'; '.join(unused) or 'none'}) names no column {shown!r}"
    return text


def is_worded_header(fields: Sequence[str], rules: Sequence[ColumnRule] = ()) -> bool:
    """True when every non-empty field is a worded header or mapped, and at least one is not skipped."""
    names = [f for f in fields if f.strip()]
    if not names:
        return False
    try:
        targets = [resolve_column(f, rules) for f in names]
    except LogFormatError:
        return True  # a worded header with a wrong unit: read_csv explains
    return all(t != "unknown" for t in targets) and any(isinstance(t, tuple) for t in targets)


def to_si(values: np.ndarray, unit: str, si: str) -> np.ndarray:
    """``values`` in ``unit`` converted to ``si`` (pint; offset units such as °C included)."""
    from motorlab.io.text import unit_factor
    from motorlab.units import registry

    if si == "K":  # temperatures: °C and °F have an offset, not a factor
        ureg = registry()
        return np.asarray(ureg.Quantity(np.asarray(values, dtype=float), unit).to(si).magnitude, dtype=float)
    factor = unit_factor(unit, si)
    return values * factor if factor != 1.0 else values
