"""Units at the edges: parse quantities given by people, convert to SI.

Everything inside motorlab is SI (rad, s, A, V, Ω, H, kg·m², N·m). Text such as ``"0.0124 kg*m^2"``,
``"400 in*oz"`` or ``"130 rpm"`` is parsed with pint and converted here, and nowhere else.
"""

from __future__ import annotations

import math
import re
from functools import lru_cache
from pathlib import Path
from typing import Any

import pint

from motorlab.errors import OptionError

_DIGIT_SEPARATOR = re.compile(r"\d_|_\d")

#: Standard gravity [m/s²], used where a mass stands for a force (scale readings, "in*oz").
STANDARD_GRAVITY = 9.80665


#: Bounds on the text of a quantity or unit (see :func:`check_expression`): characters, digits of
#: one number, size of an exponent, depth of parentheses.
MAX_QUANTITY_TEXT = 200
MAX_NUMBER_DIGITS = 40
MAX_EXPONENT = 12.0
MAX_PARENTHESES = 2

_TOKEN = re.compile(
    r"(?P<space>\s+)"
    r"|(?P<number>(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)"
    r"|(?P<power>\*\*|\^)"
    r"|(?P<op>[*/])"
    r"|(?P<open>\()"
    r"|(?P<close>\))"
    r"|(?P<sign>[+-])"
    r"|(?P<name>(?:[^\W\d]|[°%Ω\u00b5\u03bc²³])+)"
)


def check_expression(text: str) -> None:
    """Refuse a quantity or unit text that is more than numbers, unit names and the operators of a unit.

    pint evaluates what it is given as an arithmetic expression, with Python's exact integers:
    ``9**9**9`` would run for ever and ``2**1024`` overflows a float. A unit needs no more than
    products, quotients, a power by a small constant exponent (``m^2``, ``s**-1``) and
    parentheses (``(m/s)^2``), so only that is let through: at most :data:`MAX_QUANTITY_TEXT`
    characters, numbers of at most :data:`MAX_NUMBER_DIGITS` characters, an exponent that is a
    plain number of magnitude ≤ :data:`MAX_EXPONENT` and not itself raised to a power (no tower),
    parentheses at most :data:`MAX_PARENTHESES` deep, a sign only in front of a number.
    Everything it lets through is evaluated by pint in bounded work.

    Raises
    ------
    OptionError
        Saying what is not allowed (the caller adds the option's or file's name).
    """
    if len(text) > MAX_QUANTITY_TEXT:
        raise OptionError(f"longer than {MAX_QUANTITY_TEXT} characters: not a quantity")
    tokens: list[tuple[str, str]] = []
    at = 0
    while at < len(text):
        match = _TOKEN.match(text, at)
        if match is None:
            raise OptionError(f"{text[at]!r} has no place in a quantity (numbers, units, * / ^ and parentheses)")
        at = match.end()
        if match.lastgroup != "space":
            tokens.append((str(match.lastgroup), match.group()))
    depth = 0
    for k, (kind, token) in enumerate(tokens):
        before = tokens[k - 1][0] if k else ""
        if kind == "number" and len(token) > MAX_NUMBER_DIGITS:
            raise OptionError(f"the number {token[:20]}… is longer than {MAX_NUMBER_DIGITS} characters")
        if kind == "open":
            depth += 1
            if depth > MAX_PARENTHESES:
                raise OptionError(f"parentheses nested more than {MAX_PARENTHESES} deep")
        elif kind == "close":
            depth -= 1
        elif kind == "sign" and (k + 1 >= len(tokens) or tokens[k + 1][0] != "number"
                                 or before not in ("", "power", "op", "open")):
            raise OptionError(f"{token!r} only as the sign of a number (no sums in a quantity)")
        elif kind == "power":
            _check_exponent(tokens[k + 1 :])


def _check_exponent(rest: list[tuple[str, str]]) -> None:
    """The tokens after ``^``/``**``: a signed plain number of small size, not raised again."""
    sign = 1 if rest and rest[0][0] == "sign" else 0
    if len(rest) <= sign or rest[sign][0] != "number":
        raise OptionError("an exponent must be a plain number (such as m^2 or s^-1)")
    if abs(float(rest[sign][1])) > MAX_EXPONENT:
        raise OptionError(f"the exponent {rest[sign][1]} is larger than {MAX_EXPONENT:g}")
    if len(rest) > sign + 1 and rest[sign + 1][0] == "power":
        raise OptionError("a power of a power (such as 9**9**9) is not a quantity")


class _BoundedRegistry(pint.UnitRegistry):  # type: ignore[misc]
    """A pint registry that parses only what :func:`check_expression` lets through, once it is set up."""

    guarded = False

    def parse_expression(self, input_string: str, *args: Any, **kwargs: Any) -> Any:
        if self.guarded and isinstance(input_string, str):
            check_expression(input_string)
        return super().parse_expression(input_string, *args, **kwargs)

    def parse_units_as_container(self, input_string: str, *args: Any, **kwargs: Any) -> Any:
        if self.guarded and isinstance(input_string, str):
            check_expression(input_string)
        return super().parse_units_as_container(input_string, *args, **kwargs)


def _cache_folder() -> Path:
    """Where pint keeps its parsed definitions for motorlab: the user's cache folder, one per pint version."""
    import platformdirs

    return platformdirs.user_cache_path("motorlab", appauthor=False) / f"pint-{pint.__version__}"


def _new_registry() -> _BoundedRegistry:
    """pint's registry with its definitions parsed once and kept on disk (pint's ``cache_folder``): 0.05 s to set
    up instead of 0.5 s, a third of a short command's start. A cache that cannot be written or read (a read-only
    home; two processes writing it at once) is removed and the registry built from pint's own files."""
    folder = _cache_folder()
    try:
        return _BoundedRegistry(cache_folder=folder)
    except Exception:  # a cache, whatever went wrong with it: pickle's, the system's or pint's errors
        import shutil

        shutil.rmtree(folder, ignore_errors=True)
        return _BoundedRegistry()


@lru_cache(maxsize=1)
def registry() -> pint.UnitRegistry:
    """The one pint registry motorlab uses (created on first use).

    Every text it parses after its set-up, wherever it comes from (an option, a session file, a
    log's unit metadata, an environment variable), passes :func:`check_expression` first.
    """
    ureg = _new_registry()
    ureg.define("count = [] = counts = ct")
    ureg.define("rotation = revolution")  # WPILib/SysId write "Rotations"
    ureg.guarded = True
    return ureg


#: Canonical SI unit strings of the quantities motorlab stores, for display and JSON.
SI_UNITS: dict[str, str] = {
    "K": "V*s/rad",
    "R": "ohm",
    "R_dc": "ohm",
    "L": "H",
    "J": "kg*m^2",
    "b": "N*m*s/rad",
    "Tf": "N*m",
    "gamma": "1/s",
    "Tf_over_J": "rad/s^2",
    "Ka": "A/V",
    "Kt_tach": "V*s/rad",
    "kS": "V",
    "kV": "V*s/rad",
    "kA": "V*s^2/rad",
    "kG": "V",
}


def parse_quantity(value: Any, unit: str, *, name: str = "value") -> float:
    """Convert ``value`` to a float in ``unit`` (an SI unit string).

    Parameters
    ----------
    value
        A number (taken as already in ``unit``), a string holding a plain number (likewise), or a
        string with a unit that pint understands (``"400 in*oz"``, ``"130 rpm"``, ``"7.8 kg*m^2"``).
    unit
        The target unit, e.g. ``"N*m"``, ``"rad/s"``, ``"kg*m^2"``.
    name
        The option's name, used in error messages.

    Returns
    -------
    float
        The magnitude in ``unit``.

    Raises
    ------
    OptionError
        If the text is not a quantity, is not finite, or has a dimension that cannot be converted.

    Notes
    -----
    Torques written with a mass unit times a length (``in*oz``, ``kg*cm`` as printed on gearmotor
    data sheets) mean force units: they are multiplied by standard gravity g₀ = 9.80665 m/s², as
    seed 1 does by hand ("400 in·oz ... 0.454 kg·9.81 m/s²").
    """
    if isinstance(value, bool):
        raise OptionError(f"{name}: expected a quantity in {unit}, got {value!r}")
    if isinstance(value, int | float):
        try:
            number = float(value)
        except OverflowError:  # an int beyond a float (a TOML integer of 400 digits)
            raise OptionError(f"{name}: {_shown(str(value))} is not a finite number") from None
    else:
        text = str(value).strip()
        if _DIGIT_SEPARATOR.search(text):  # Python and pint read "1_0" as 10: refuse, do not guess
            raise OptionError(f"{name}: {_shown(text)!r} is not a number (no '_' between digits)")
        try:
            number = float(text)
        except ValueError:
            number = _parse_with_pint(text, unit, name)
    if not math.isfinite(number):
        raise OptionError(f"{name}: {_shown(str(value))!r} is not a finite number")
    return number


def _shown(text: str) -> str:
    """``text`` cut to 60 characters for a message (a 5,000-digit number is not shown whole)."""
    return text if len(text) <= 60 else text[:57] + "..."


def _parse_with_pint(text: str, unit: str, name: str) -> float:
    ureg = registry()
    shown = _shown(text)
    try:
        check_expression(text)
        quantity: Any = ureg.Quantity(text)
    except OptionError as exc:
        raise OptionError(f"{name}: cannot read {shown!r} as a quantity in {unit}: {exc.message}") from None
    except OverflowError:  # 1e200^2: beyond a float
        raise OptionError(f"{name}: {shown!r} is not a finite number") from None
    except Exception as exc:  # pint raises several unrelated types for bad text
        raise OptionError(f"{name}: cannot read {shown!r} as a quantity in {unit} ({exc})") from None
    target = ureg.Quantity(1.0, unit)
    try:
        if not isinstance(quantity, pint.Quantity):
            return float(quantity)
        try:
            return float(quantity.to(unit).magnitude)
        except pint.DimensionalityError:
            pass
        # A mass standing for a weight: in*oz, kg*cm (torque) or g, kg (force).
        weighted = quantity * ureg.Quantity(STANDARD_GRAVITY, "m/s^2")
        if weighted.dimensionality == target.dimensionality:
            return float(weighted.to(unit).magnitude)
    except (OverflowError, ValueError, ZeroDivisionError):  # 2**1024 or 1e308^2: beyond a float
        raise OptionError(f"{name}: {shown!r} is not a finite number") from None
    raise OptionError(
        f"{name}: {text!r} has units of {quantity.units:~P}, which cannot be converted to {unit}"
    )


def format_percent(fraction: float, spec: str = ".2f") -> str:
    """``100·fraction`` as ``"12.34 %"``, or ``"? %"`` when it is not a finite number (never "nan %")."""
    value = 100.0 * float(fraction)
    return f"{value:{spec}} %" if math.isfinite(value) else "? %"


def format_unit(unit: str) -> str:
    """A unit string as printed for people: ``"N*m*s/rad"`` -> ``"N·m·s/rad"``."""
    return unit.replace("**", "^").replace("*", "·").replace("^2", "²").replace("ohm", "Ω")


#: Digits and minus sign as superscripts, for powers of ten written as people write them (× 10⁻⁵).
SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


def power_of_ten(exponent: int) -> str:
    """``"10⁻⁵"`` for -5."""
    return "10" + str(int(exponent)).translate(SUPERSCRIPT)


def format_value(value: float, stderr: float, *, scale: float = 1.0) -> str:
    """``"0.3712 ± 0.0021"``: the value to the precision of its standard error (2 significant digits); one power of
    ten for both where fixed decimals would take more than six (``"(1.44627 ± 0.00015) × 10⁻²"``, as the app writes
    it).

    Parameters
    ----------
    value, stderr
        In SI.
    scale
        Display scale (1e6 for µH).
    """
    if not math.isfinite(value):
        return "—"
    v = value * scale
    if not (math.isfinite(stderr) and stderr > 0):
        return f"{v:.4g}"
    s = stderr * scale
    exponent = math.floor(math.log10(abs(s))) - 1
    decimals = max(-exponent, 0)
    if abs(v) >= 1e5 or decimals > 6:
        # One power of ten, the mantissa's digits set by the error: (7.865 ± 0.011) × 10⁻⁵.
        e = math.floor(math.log10(abs(v))) if v != 0 else exponent + 1  # zero: the error's power
        digits = max(e - exponent, 1)
        return f"({v / 10**e:.{digits}f} ± {s / 10**e:.{digits}f}) × {power_of_ten(e)}"
    return f"{v:.{decimals}f} ± {s:.{decimals}f}"
