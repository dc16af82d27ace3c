"""Road Runner 1.0 tuning files: the forward, lateral and angular ramp logs (JSON).

Road Runner's tuning OpModes (``ForwardRampLogger``, ``LateralRampLogger``, ``AngularRampLogger`` in
road-runner-ftc ``RoadRunner/src/main/java/com/acmerobotics/roadrunner/ftc/Tuning.kt``) ramp the drive
power by ``POWER_PER_SEC`` (0.1 /s) up to ``POWER_MAX`` (0.9) and save, when the OpMode stops, one
JSON file under ``RoadRunner/tuning/<forward-ramp|lateral-ramp|angular-ramp>/<millis>.json``
(``FileServing.kt``, ``TuningFiles.save``, Jackson's pretty printer). Every signal is an object
``{"times": [...], "values": [...]}``, times in seconds from the OpMode's start (``MidpointTimer``).
Field names, the 16-bit velocity repair and the samples dropped are those of the tuning page
(``web/tuning/common.ts``); see ``docs/formats.md`` for the field list and the commits read.

What this reader does, and why:

* applied voltage = power × battery voltage (``voltages``, the hub's ``VoltageSensor`` read in the
  same loop iteration), as the tuning page computes it;
* encoder velocities flagged ``*EncFixVels`` (every encoder of a REV hub; a missing flag means true,
  as on the page) are 16-bit integers on the wire and wrap at ±2¹⁵ ticks/s: they are recovered with
  the positions (:func:`repair_velocity`), never dropped;
* like the page, the first sample and the last two are dropped (the last loop iteration may be cut
  short when the OpMode stops);
* positions are in encoder ticks: ``cpr`` (counts per revolution of that encoder) turns them into
  the encoder's angle [rad].
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from motorlab.errors import LogFormatError, OptionError
from motorlab.io.output import check_writable_target
from motorlab.io.text import PathArg, check_cpr, load_json, read_bytes
from motorlab.recording import Recording

#: Ramp kinds and a key only that kind's file has.
KINDS = {"forward": "forwardEncPositions", "lateral": "perpEncPositions", "angular": "angVels"}
#: Encoder groups of each kind (``<group>EncPositions``, ``<group>EncVels``, ``<group>EncFixVels``).
GROUPS = {"forward": ("forward",), "lateral": ("perp",), "angular": ("left", "right", "par", "perp")}
#: Power signals of each kind (a list of signals, or single signals for the lateral ramp).
POWERS = {
    "forward": ("powers",),
    "lateral": ("frontLeftPower", "backLeftPower", "frontRightPower", "backRightPower"),
    "angular": ("leftPowers", "rightPowers"),
}
#: One velocity step of the hub's 16-bit register [ticks/s].
WRAP = 2**16
#: The hub counts over a 50 ms window and reports 20 × counts: real velocities are multiples of 20.
HUB_VELOCITY_QUANTUM = 20


@dataclass
class RampData:
    """A Road Runner ramp log, aligned by loop iteration (first sample and last two dropped).

    Attributes
    ----------
    kind
        ``"forward"``, ``"lateral"`` or ``"angular"``.
    drive
        ``"mecanum"`` or ``"tank"``.
    time
        Encoder read times [s] (the first encoder group's bulk read of each iteration).
    battery
        Battery voltage read by the hub in each iteration [V].
    powers
        Motor powers by name (``powers0``, ``frontLeftPower``, ``leftPowers1`` ...), −1 … 1.
    positions, velocities
        Encoder positions [ticks] and repaired velocities [ticks/s] by name (``forward0``, ``perp0``,
        ``left1`` ...); a velocity missing from the file is the central difference of the positions.
    repaired
        Names of the encoders whose velocities were unwrapped, with how many samples changed.
    ang_vels
        IMU angular velocities about x, y, z [rad/s] (angular ramp only).
    power_times, voltage_time
        The logged ``MidpointTimer`` times of each power signal and of the battery reading [s].
    """

    kind: str
    drive: str
    time: np.ndarray
    battery: np.ndarray
    powers: dict[str, np.ndarray]
    positions: dict[str, np.ndarray]
    velocities: dict[str, np.ndarray]
    repaired: dict[str, int] = field(default_factory=dict)
    ang_vels: list[np.ndarray] = field(default_factory=list)
    source: str = ""
    power_times: dict[str, np.ndarray] = field(default_factory=dict)
    voltage_time: np.ndarray | None = None


def repair_velocity(raw: np.ndarray, estimate: np.ndarray) -> np.ndarray:
    """Undo the 16-bit wrap of hub velocities [ticks/s] with an estimate from the positions.

    Parameters
    ----------
    raw
        Velocities as logged (the hub's 16-bit value, sign-extended and maybe negated) [ticks/s].
    estimate
        Velocities from the positions (central differences) [ticks/s].

    Returns
    -------
    numpy.ndarray
        ``raw + k·2¹⁶`` with the integer k that makes the value a multiple of 20 (the hub's 50 ms
        window) nearest to ``estimate``; without the multiple-of-20 pattern (not a hub), the nearest
        ``raw + k·2¹⁶``.

    Notes
    -----
    The same recovery as Road Runner's ``inverseOverflow`` (road-runner-ftc ``Encoders.kt`` and
    ``web/tuning/common.ts``): 2¹⁶ ≡ 16 (mod 20), so the residue of the wrapped value modulo 20 gives
    k modulo 5, and the estimate need only be right to within ±2.5·2¹⁶ ticks/s.
    """
    raw = np.asarray(raw, dtype=float)
    est = np.asarray(estimate, dtype=float)
    base = np.round(raw)
    k_near = np.round((est - base) / WRAP)
    out = base + k_near * WRAP
    hub = np.all(np.mod(base, 4) == 0)
    if hub:
        # candidates base + k·2¹⁶ that are multiples of 20: k ≡ k0 (mod 5)
        best = np.full(base.shape, np.nan)
        for dk in range(-3, 4):
            k = k_near + dk
            cand = base + k * WRAP
            ok = np.mod(cand, HUB_VELOCITY_QUANTUM) == 0
            better = ok & (np.isnan(best) | (np.abs(cand - est) < np.abs(best - est)))
            best = np.where(better, cand, best)
        out = np.where(np.isnan(best), out, best)
    return out


def central_difference(time: np.ndarray, values: np.ndarray) -> np.ndarray:
    """d(values)/dt by central differences (one-sided at the ends), as the tuning page estimates it."""
    t = np.asarray(time, dtype=float)
    x = np.asarray(values, dtype=float)
    if t.size < 2:
        return np.zeros_like(x)
    return np.gradient(x, t)


def _line_of(text: str, key: str) -> int | None:
    match = re.search(r'"' + re.escape(key) + r'"\s*:', text)
    return None if match is None else text.count("\n", 0, match.start()) + 1


class _Parser:
    """Validating access to the decoded JSON, errors naming the file, line and field."""

    def __init__(self, name: str, data: dict[str, Any], text: str):
        self.name, self.data, self.text = name, data, text

    def fail(self, key: str, problem: str) -> LogFormatError:
        return LogFormatError(f"{key}: {problem}", path=self.name, line=_line_of(self.text, key.split("[")[0]))

    def get(self, key: str) -> Any:
        if key not in self.data:
            raise LogFormatError(f"a Road Runner ramp log needs {key!r}", path=self.name)
        return self.data[key]

    def signal(self, value: Any, key: str) -> tuple[np.ndarray, np.ndarray]:
        if not isinstance(value, dict) or "times" not in value or "values" not in value:
            raise self.fail(key, 'expected a signal {"times": [...], "values": [...]}')
        try:
            times = np.asarray(value["times"], dtype=float)
            values = np.asarray(value["values"], dtype=float)
        except (TypeError, ValueError):
            raise self.fail(key, "times and values must be lists of numbers") from None
        if times.ndim != 1 or values.ndim != 1 or times.size != values.size:
            raise self.fail(key, f"{times.size} times but {values.size} values")
        if not (np.all(np.isfinite(times)) and np.all(np.isfinite(values))):
            raise self.fail(key, "a time or value is not a finite number")
        return times, values

    def signals(self, key: str) -> list[tuple[np.ndarray, np.ndarray]]:
        value = self.get(key)
        if isinstance(value, dict):  # the lateral ramp's single power signals
            return [self.signal(value, key)]
        if not isinstance(value, list):
            raise self.fail(key, "expected a list of signals")
        return [self.signal(v, f"{key}[{i}]") for i, v in enumerate(value)]

    def flags(self, key: str, count: int) -> list[bool]:
        value = self.data.get(key)
        if value is None:  # older files: the tuning page repairs every encoder
            return [True] * count
        if not isinstance(value, list) or len(value) != count or not all(isinstance(v, bool) for v in value):
            raise self.fail(key, f"expected {count} true/false flags")
        return list(value)


def ramp_kind(data: Any) -> str | None:
    """``"forward"``, ``"lateral"``, ``"angular"`` for a decoded Road Runner ramp log, else None."""
    if not isinstance(data, dict) or "voltages" not in data:
        return None
    for kind, key in (("angular", KINDS["angular"]), ("forward", KINDS["forward"]), ("lateral", KINDS["lateral"])):
        if key in data:
            return kind
    return None


def _load(path: PathArg) -> tuple[str, dict[str, Any], str]:
    name, raw = read_bytes(path)
    if not raw.strip():
        raise LogFormatError("the file is empty", path=name)
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise LogFormatError("not a text file (invalid UTF-8)", path=name) from None
    data = load_json(text, name)
    if ramp_kind(data) is None:
        raise LogFormatError(
            "not a Road Runner ramp log (expected 'voltages' and 'forwardEncPositions', "
            "'perpEncPositions' or 'angVels')", path=name, line=1)
    return name, data, text


def _trim(n: int) -> slice:
    """The tuning page's trim: drop the first sample and the last two."""
    return slice(1, max(1, n - 2))


def read_ramp_data(path: PathArg) -> RampData:
    """Parse and align a Road Runner ramp log (see :class:`RampData`).

    Raises
    ------
    LogFormatError
        Not JSON, not a ramp log, a missing field, signals of different lengths, non-finite values,
        time not increasing, or fewer than 10 samples.
    """
    name, data, text = _load(path)
    p = _Parser(name, data, text)
    kind = ramp_kind(data)
    assert kind is not None
    drive = str(p.get("type")).lower()
    if drive not in ("mecanum", "tank"):  # Jackson writes the enum's name (MECANUM); the page expects lowercase
        raise p.fail("type", f"drive type {data['type']!r} is neither mecanum nor tank")
    battery_t, battery = p.signal(p.get("voltages"), "voltages")
    n = battery.size
    powers: dict[str, np.ndarray] = {}
    power_times: dict[str, np.ndarray] = {}
    for key in POWERS[kind]:
        for i, (times, values) in enumerate(p.signals(key)):
            label = key if kind == "lateral" else f"{key}{i}"
            powers[label] = values
            power_times[label] = times
    positions: dict[str, np.ndarray] = {}
    velocities: dict[str, np.ndarray] = {}
    repaired: dict[str, int] = {}
    enc_time: np.ndarray | None = None
    for group in GROUPS[kind]:
        pos = p.signals(f"{group}EncPositions")
        vel = p.signals(f"{group}EncVels")
        if len(vel) != len(pos):
            raise p.fail(f"{group}EncVels", f"{len(vel)} velocity signals for {len(pos)} encoders")
        fix = p.flags(f"{group}EncFixVels", len(pos))
        for i, ((t, x), (_tv, v)) in enumerate(zip(pos, vel, strict=True)):
            label = f"{group}{i}"
            est = central_difference(t, x) if t.size > 1 and np.all(np.diff(t) > 0) else np.zeros_like(x)
            if v.size == 0:  # encoders without velocity: the page differentiates the positions
                v = est
            elif v.size != x.size:
                raise p.fail(f"{group}EncVels[{i}]", f"{v.size} velocities for {x.size} positions")
            elif fix[i]:
                fixed = repair_velocity(v, est)
                changed = int(np.count_nonzero(fixed != np.round(v)))
                if changed:
                    repaired[label] = changed
                v = fixed
            positions[label], velocities[label] = x, v
            if enc_time is None:
                enc_time = t
    ang = [values for _, values in p.signals("angVels")] if kind == "angular" else []
    lengths = {"voltages": n, **{k: v.size for k, v in powers.items()}, **{k: v.size for k, v in positions.items()}}
    if kind == "angular":
        lengths.update({f"angVels[{i}]": a.size for i, a in enumerate(ang)})
    if len(set(lengths.values())) > 1:
        raise LogFormatError(
            "signals of different lengths: " + ", ".join(f"{k} {v}" for k, v in lengths.items()), path=name)
    if enc_time is None:
        raise LogFormatError(f"the {kind} ramp log has no encoders", path=name, line=_line_of(text, KINDS[kind]))
    keep = _trim(n)
    time = enc_time[keep]
    if time.size < 10:
        raise LogFormatError(f"{time.size} samples after the first and last two are dropped: at least 10 "
                             "are needed", path=name)
    bad = np.flatnonzero(~(np.diff(time) > 0))
    if bad.size:
        raise LogFormatError(f"encoder times do not increase (sample {bad[0] + 2})", path=name,
                             line=_line_of(text, f"{GROUPS[kind][0]}EncPositions"))
    return RampData(
        kind=kind, drive=drive, time=time, battery=battery[keep],
        powers={k: v[keep] for k, v in powers.items()},
        positions={k: v[keep] for k, v in positions.items()},
        velocities={k: v[keep] for k, v in velocities.items()},
        repaired=repaired, ang_vels=[a[keep] for a in ang], source=name,
        power_times={k: v[keep] for k, v in power_times.items()}, voltage_time=battery_t[keep],
    )


def signed_powers(data: RampData) -> dict[str, np.ndarray]:
    """Each motor's power with the sign that drives the ramp's motion (Tuning.kt's power signs).

    Forward ramp: the powers; lateral: −frontLeft, backLeft, frontRight, −backRight; angular: the
    right-side powers and the negated left-side ones.
    """
    flip = {"frontLeftPower", "backRightPower"} if data.kind == "lateral" else set()
    out = {}
    for k, v in data.powers.items():
        sign = -1.0 if k in flip or (data.kind == "angular" and k.startswith("leftPowers")) else 1.0
        out[k] = sign * v
    return out


def drive_voltage(data: RampData) -> np.ndarray:
    """Applied voltage [V]: battery × the mean power driving the motion (negative values clipped).

    The tuning page takes the largest power. The logger evaluates ``power(t.seconds())`` afresh for
    each motor (Tuning.kt), so on a ramp the powers of one iteration differ by a few milliseconds of
    ramp (the last motor's is the largest), and the chassis, which the motors push together, sees
    their mean.
    """
    stack = np.vstack(list(signed_powers(data).values()))
    return np.maximum(np.mean(stack, axis=0), 0.0) * data.battery


def power_effect_times(data: RampData) -> dict[str, np.ndarray]:
    """When each logged power took effect [s], from the ``MidpointTimer`` splits.

    Tuning.kt calls ``addSplit()`` after each ``setPower``, and a split's time is the midpoint of
    the interval since the previous split. For every motor but the first, that interval is its own
    ``setPower`` (a Lynx round trip, during which the hub applies the power): its midpoint is taken
    as the moment the power changed. The first motor's interval starts at the previous iteration's
    last split and includes whatever the loop did in between (loop overhead, another encoder group's
    bulk read, a team's own code), so its midpoint can be many milliseconds early; it is
    extrapolated from the next two splits (commands of equal length): τ₀ = 2·m₁ − m₂, m₂ being the
    battery read's split when there are only two motors.
    """
    if not data.power_times:
        return {}
    order = sorted(data.power_times, key=lambda k: float(np.mean(data.power_times[k])))
    later = [data.power_times[k] for k in order[1:]]
    if data.voltage_time is not None:
        later.append(data.voltage_time)
    out = {k: data.power_times[k] for k in order}
    if len(later) >= 2:
        out[order[0]] = np.minimum(2.0 * later[0] - later[1], later[0])
    return out


def held_voltage(data: RampData) -> np.ndarray:
    """Applied voltage over each encoder interval [t_k, t_k+1) [V], the powers held as the hub holds them.

    A motor's power of iteration k+1 takes effect (:func:`power_effect_times`) a few ms before that
    iteration's encoder read t_k+1, so over [t_k, t_k+1) the motor holds P_k·(1 − f) + P_k+1·f on
    average, f the share of the interval after the change. Assigning each iteration's power to its
    encoder read instead puts the voltage a few ms late, which on a ramp (1.3 V/s) reads as kS about
    1 % high per 2.5 ms. The drive voltage is the motors' mean held power times the battery reading
    B_k of the iteration, as read: neither smoothed nor mixed with the next reading. The fit
    estimates the voltage noise from the sample-to-sample differences of its input and takes it as
    white; averaging readings (smoothing, or mixing B_k and B_k+1 like the powers) hides most of that
    noise from the estimate while leaving its slow part, which is what moves the gains: the
    standard errors came out 2.4 times too small at a fixed loop period.
    """
    t = data.time
    effect = power_effect_times(data)
    mixed = []
    for name, pw in signed_powers(data).items():
        held = pw.copy()
        if name in effect and t.size > 1:
            frac = np.clip((t[1:] - effect[name][1:]) / np.diff(t), 0.0, 1.0)
            held[:-1] = pw[:-1] * (1.0 - frac) + pw[1:] * frac
        mixed.append(held)
    return np.maximum(np.mean(mixed, axis=0), 0.0) * data.battery


def motion_counts(data: RampData) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Position [ticks] and velocity [ticks/s] of the motion the voltage drives, and the encoders used.

    Forward ramp: mean of the forward encoders; lateral: mean of the perpendicular encoders;
    angular with drive encoders: mean of (−left, +right) wheel ticks. Angular with dead wheels has
    no such encoder (empty list).
    """
    if data.kind == "angular":
        names = [k for k in data.positions if k.startswith(("left", "right"))]
        signs = [-1.0 if k.startswith("left") else 1.0 for k in names]
    else:
        names = list(data.positions)
        signs = [1.0] * len(names)
    if not names:
        return np.zeros(0), np.zeros(0), []
    pos = np.mean([s * data.positions[k] for s, k in zip(signs, names, strict=True)], axis=0)
    vel = np.mean([s * data.velocities[k] for s, k in zip(signs, names, strict=True)], axis=0)
    return pos, vel, names


def read_roadrunner_ramp(path: PathArg, *, cpr: float | None = None) -> Recording:
    """Read a Road Runner 1.0 forward / lateral / angular ramp log into a :class:`Recording`.

    Parameters
    ----------
    path
        The ``.json`` file the tuning OpMode saved (``RoadRunner/tuning/forward-ramp/…``).
    cpr
        Counts per revolution of the encoders the positions come from (dead wheels or drive motors);
        required: the file counts ticks.

    Returns
    -------
    Recording
        ``time`` [s]; ``voltage`` = power × battery [V]; ``battery`` [V]; ``position`` [rad] and
        ``counts`` (mean of the encoders that see the driven motion); ``velocity`` [rad/s] (their
        repaired hub velocities). ``metadata``: ``format`` ``"roadrunner-ramp"``, ``ramp`` (kind),
        ``drive``, ``cpr``, ``encoders``, ``repaired`` and the parsed :class:`RampData` under
        ``"roadrunner"``.

    Raises
    ------
    LogFormatError
        See :func:`read_ramp_data`.
    OptionError
        Without ``cpr``.
    """
    cpr = check_cpr(cpr)
    data = read_ramp_data(path)
    if cpr is None:
        raise OptionError(
            f"{data.source}: a Road Runner ramp log counts encoder ticks: give --cpr (counts per revolution "
            "of the encoder: dead wheel or drive motor)")
    per_tick = 2 * math.pi / cpr
    counts, vel, names = motion_counts(data)
    signals = {"voltage": held_voltage(data), "battery": data.battery}
    warnings = []
    if names:
        signals.update(position=counts * per_tick, counts=counts, velocity=vel * per_tick)
    if data.repaired:
        warnings.append(
            f"{data.source}: 16-bit velocity overflow repaired from the positions ("
            + ", ".join(f"{k}: {v} samples" for k, v in data.repaired.items()) + ")")
    meta = {
        "format": "roadrunner-ramp", "ramp": data.kind, "drive": data.drive, "cpr": cpr,
        "encoders": names, "repaired": dict(data.repaired), "roadrunner": data, "warnings": warnings,
        "position_unit": "rad",
    }
    return Recording(time=data.time, signals=signals, metadata=meta, source=data.source)


# ---- writer (the virtual rig's) ------------------------------------------------------------------


def _signal(times: np.ndarray, values: np.ndarray) -> dict[str, list[float]]:
    return {"times": [float(t) for t in times], "values": [float(v) for v in values]}


def write_roadrunner_ramp(path: PathArg, content: dict[str, Any]) -> None:
    """Write a ramp log as Road Runner's ``TuningFiles.save`` does (Jackson's default pretty printer).

    ``content`` maps the file's field names to arrays: a signal is a ``(times, values)`` pair, a
    list of them a list of signals; ``type`` is the drive type string; ``*EncFixVels`` lists of bool.
    """
    out: dict[str, Any] = {}
    for key, value in content.items():
        if isinstance(value, tuple):
            out[key] = _signal(*value)
        elif isinstance(value, list) and value and isinstance(value[0], tuple):
            out[key] = [_signal(*v) for v in value]
        else:
            out[key] = value
    check_writable_target(path)
    with open(path, "w", encoding="utf-8") as handle:
        handle.write(_jackson(out, 0))


def _jackson(value: Any, depth: int) -> str:
    """JSON in the layout of Jackson's ``DefaultPrettyPrinter``: objects one field a line, arrays inline."""
    pad = "  " * depth
    if isinstance(value, dict):
        if not value:
            return "{ }"
        fields = [f'{pad}  {json.dumps(k)} : {_jackson(v, depth + 1)}' for k, v in value.items()]
        return "{\n" + ",\n".join(fields) + f"\n{pad}}}"
    if isinstance(value, list):
        if not value:
            return "[ ]"
        return "[ " + ", ".join(_jackson(v, depth) for v in value) + " ]"
    return json.dumps(value)
