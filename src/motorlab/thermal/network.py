"""Heat: the winding's temperature, and what it does to R and K.

A brushed DC motor's winding is copper: its resistance rises by α = +0.393 %/K (IEC 60028, annealed
copper at 20 °C); the permanent magnets weaken as they warm, K falling by β ≈ −0.2 %/K (ferrite) or
−0.12 %/K (sintered NdFeB). The heat I²·R goes into a thermal network of two nodes (Cauer ladder)::

    C_w·dT_w/dt = R(T_w)·i² − (T_w − T_c)/R_wc           winding (armature copper and iron)
    C_c·dT_c/dt = (T_w − T_c)/R_wc − (T_c − T_a)/R_ca      case (housing, magnets, brush gear)
    R(T_w) = R₂₅·(1 + α·(T_w − 25 °C)),   K(T_c) = K₂₅·(1 + β·(T_c − 25 °C))

The magnets sit on the housing, so K follows the case node. Temperatures are in °C (differences in K);
R and K of a :class:`~motorlab.model.MotorParams` that carries a :class:`ThermalModel` are their values
at the reference temperature (25 °C).

Between samples the power is held at its value at the midpoint temperature (predicted with the
derivative at the start), and the linear network is advanced exactly with its two modes: second-order
accurate in the step, and exact for a constant power whatever the step.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace
from functools import cached_property
from typing import Any

import numpy as np

from motorlab.errors import OptionError

#: Temperature coefficient of copper's resistance [1/K] (IEC 60028: 0.00393 /K for annealed copper).
COPPER_COEFFICIENT = 0.00393
#: Reversible temperature coefficients of the remanence of permanent magnets [1/K] (makers' tables:
#: hard ferrite −0.18 to −0.20 %/K, sintered NdFeB −0.09 to −0.12 %/K; e.g. Arnold Magnetic
#: Technologies' and TDK's material data sheets). K is proportional to the air-gap flux.
MAGNET_COEFFICIENTS = {"ferrite": -0.0020, "ndfeb": -0.0012}
#: The temperature at which R and K of a thermal model are given [°C].
REFERENCE_TEMPERATURE = 25.0
#: A winding's usual limit [°C]: enamelled wire of thermal class 155 (F) or 180 (H); the stall-time
#: answer uses 150 °C unless told otherwise.
WINDING_LIMIT = 150.0


@dataclass(frozen=True)
class ThermalModel:
    """Two-node thermal network of a motor (winding → case → ambient) and its temperature coefficients.

    Parameters
    ----------
    winding_to_case
        Thermal resistance R_wc from the winding to the case [K/W].
    case_to_ambient
        Thermal resistance R_ca from the case to the ambient air [K/W].
    winding_capacity
        Heat capacity C_w of the winding node (copper and armature iron) [J/K].
    case_capacity
        Heat capacity C_c of the case node (housing, magnets; a gearbox bolted on adds to it) [J/K].
    magnet_coefficient
        β: relative change of K per kelvin of the case [1/K] (ferrite −0.002, NdFeB −0.0012).
    resistance_coefficient
        α: relative change of R per kelvin of the winding [1/K] (copper 0.00393).
    ambient_temperature
        Temperature of the surroundings T_a [°C].
    """

    winding_to_case: float
    case_to_ambient: float
    winding_capacity: float
    case_capacity: float
    magnet_coefficient: float = MAGNET_COEFFICIENTS["ferrite"]
    resistance_coefficient: float = COPPER_COEFFICIENT
    ambient_temperature: float = REFERENCE_TEMPERATURE

    def __post_init__(self) -> None:
        for name in ("winding_to_case", "case_to_ambient", "winding_capacity", "case_capacity"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise OptionError(f"thermal model: {name} must be positive and finite, got {value!r}")
        if not (math.isfinite(self.magnet_coefficient) and -0.01 < self.magnet_coefficient <= 0.001):
            raise OptionError(f"thermal model: magnet coefficient {self.magnet_coefficient!r} /K is not a magnet's "
                              "(ferrite −0.002, NdFeB −0.0012)")
        if not (math.isfinite(self.resistance_coefficient) and 0 <= self.resistance_coefficient < 0.01):
            raise OptionError(f"thermal model: resistance coefficient {self.resistance_coefficient!r} /K is not a "
                              "metal's (copper 0.00393)")
        if not (math.isfinite(self.ambient_temperature) and -60 <= self.ambient_temperature <= 200):
            raise OptionError(f"thermal model: ambient temperature {self.ambient_temperature!r} °C is out of range")

    # ---- construction ------------------------------------------------------------------------
    @classmethod
    def from_dict(cls, values: dict[str, Any]) -> ThermalModel:
        """From :meth:`to_dict`'s form (numbers, or ``{"value": ...}`` as ``analyze --json`` writes them)."""
        kwargs: dict[str, float] = {}
        for name in cls.__dataclass_fields__:
            if name in values and values[name] is not None:
                v = values[name]
                try:
                    kwargs[name] = float(v["value"] if isinstance(v, dict) else v)
                except (TypeError, ValueError, KeyError):
                    raise OptionError(f"thermal model: {name} is not a number: {v!r}") from None
        missing = [n for n in ("winding_to_case", "case_to_ambient", "winding_capacity", "case_capacity")
                   if n not in kwargs]
        if missing:
            raise OptionError("thermal model: missing " + ", ".join(missing))
        return cls(**kwargs)

    def to_dict(self) -> dict[str, float]:
        """Plain dict of the figures (K/W, J/K, 1/K, °C)."""
        return asdict(self)

    def with_ambient(self, temperature: float) -> ThermalModel:
        """A copy at another ambient temperature [°C]."""
        return replace(self, ambient_temperature=float(temperature))

    # ---- coefficients --------------------------------------------------------------------------
    def resistance_factor(self, winding_temperature: Any) -> Any:
        """R(T)/R₂₅ = 1 + α·(T − 25 °C)."""
        return 1.0 + self.resistance_coefficient * (winding_temperature - REFERENCE_TEMPERATURE)

    def constant_factor(self, case_temperature: Any) -> Any:
        """K(T)/K₂₅ = 1 + β·(T − 25 °C)."""
        return 1.0 + self.magnet_coefficient * (case_temperature - REFERENCE_TEMPERATURE)

    # ---- the network -----------------------------------------------------------------------------
    @cached_property
    def _modes(self) -> tuple[float, float, np.ndarray, np.ndarray, np.ndarray]:
        """Eigenvalues λ₁, λ₂ [1/s], eigenvectors W, W⁻¹ and W⁻¹·B of x' = A·x + B·P (x = T − T_a).

        A = [[−p, p], [q, −q − s]] (p = 1/(C_w·R_wc), q = 1/(C_c·R_wc), s = 1/(C_c·R_ca)), a passive RC ladder: its
        eigenvalues are real, negative and distinct, in closed form (the larger root without cancellation, the
        other from the determinant; a heating fit builds a network for every parameter vector it tries, where
        numpy's eig and inv took a tenth of the stall fits' time), each eigenvector (p, p + λ) from the first row.
        """
        rwc, rca, cw, cc = self.winding_to_case, self.case_to_ambient, self.winding_capacity, self.case_capacity
        p, q, s = 1.0 / (cw * rwc), 1.0 / (cc * rwc), 1.0 / (cc * rca)
        half = -0.5 * (p + q + s)
        root = math.sqrt(0.25 * (p - q - s) ** 2 + p * q)
        lam1 = half - root  # the fast (winding) mode
        lam2 = p * s / lam1  # λ₁·λ₂ = det A = p·s
        det = p * (lam2 - lam1)
        w = np.array([[p, p], [p + lam1, p + lam2]])
        winv = np.array([[p + lam2, -p], [-(p + lam1), p]]) / det
        return lam1, lam2, w, winv, winv @ np.array([1 / cw, 0.0])

    @property
    def time_constants(self) -> tuple[float, float]:
        """The network's two time constants [s], fast (winding) first."""
        lam1, lam2 = self._modes[:2]
        return tuple(sorted((-1 / lam1, -1 / lam2)))  # type: ignore[return-value]

    def step(self, winding: float, case: float, power: float, duration: float) -> tuple[float, float]:
        """Winding and case temperatures [°C] after ``duration`` [s] of a constant ``power`` [W] into the winding."""
        lam1, lam2, w, winv, g = self._modes
        ta = self.ambient_temperature
        z1 = winv[0, 0] * (winding - ta) + winv[0, 1] * (case - ta)
        z2 = winv[1, 0] * (winding - ta) + winv[1, 1] * (case - ta)
        e1, e2 = math.exp(lam1 * duration), math.exp(lam2 * duration)
        z1 = e1 * z1 + (e1 - 1) / lam1 * g[0] * power
        z2 = e2 * z2 + (e2 - 1) / lam2 * g[1] * power
        return ta + w[0, 0] * z1 + w[0, 1] * z2, ta + w[1, 0] * z1 + w[1, 1] * z2

    def steady_rise(self, power: float) -> tuple[float, float]:
        """Steady rises of the winding and the case over ambient [K] under a constant ``power`` [W]."""
        return power * (self.winding_to_case + self.case_to_ambient), power * self.case_to_ambient

    def energy_rise(self, energy: float) -> float:
        """Rise of the winding [K] if ``energy`` [J] went into it with no time to flow out: E/C_w (an upper
        bound for short runs; the whole motor's capacity C_w + C_c bounds it from below)."""
        return energy / self.winding_capacity


@dataclass
class StallRun:
    """A stall at held voltages, integrated: times [s], current [A], winding and case temperatures [°C]."""

    time: np.ndarray
    current: np.ndarray
    winding_temperature: np.ndarray
    case_temperature: np.ndarray


def stall_response(
    resistance: float, thermal: ThermalModel, time: np.ndarray, voltage: np.ndarray, *,
    winding: float, case: float | None = None, current_limit: float | None = None, series_resistance: float = 0.0,
) -> StallRun:
    """Current and temperatures of a stalled motor under held terminal voltages.

    Parameters
    ----------
    resistance
        R₂₅, the winding's resistance at 25 °C [Ω].
    thermal
        The thermal network and coefficients.
    time
        Sample times [s], increasing.
    voltage
        Terminal voltage at each sample, held until the next [V].
    winding, case
        Initial temperatures [°C] (``case`` defaults to ``winding``: a motor at rest long enough).
    current_limit
        A supply's current limit [A]: beyond it the current is held at the limit (constant current).
    series_resistance
        A resistance in series with the winding that does not follow its temperature [Ω] (the brushes'
        contact, as a forecast carries it on from a fitted run); its heat is counted with the winding's.

    Notes
    -----
    The rotor is still, so i = V/R(T_w) (L/R ≈ 1 ms is far shorter than any sample interval), the heat
    is V·i, and the network is advanced exactly over each interval with the heat at the predicted
    midpoint temperature. A plain Python loop over floats: ~1 µs per sample.
    """
    lam1, lam2, w, winv, g = thermal._modes
    ta, alpha = thermal.ambient_temperature, thermal.resistance_coefficient
    cw, rwc = thermal.winding_capacity, thermal.winding_to_case
    w00, w01, w10, w11 = float(w[0, 0]), float(w[0, 1]), float(w[1, 0]), float(w[1, 1])
    tc0 = winding if case is None else case
    z1 = float(winv[0, 0] * (winding - ta) + winv[0, 1] * (tc0 - ta))
    z2 = float(winv[1, 0] * (winding - ta) + winv[1, 1] * (tc0 - ta))
    t_arr = np.asarray(time, dtype=float)
    n = t_arr.size
    h_arr = np.diff(t_arr)
    e1, e2 = np.exp(lam1 * h_arr), np.exp(lam2 * h_arr)
    # In the modal coordinates z the resistance is affine, R = r0 + q1·z1 + q2·z2, and so is the winding's flow to
    # the case, (T_w − T_c)/R_wc = d1·z1 + d2·z2; R at the predicted midpoint is R + (∂R/∂T_w)·ΔT_w.
    r25, tref, rs = float(resistance), REFERENCE_TEMPERATURE, float(series_resistance)
    slope = r25 * alpha
    r0 = r25 * (1.0 + alpha * (ta - tref)) + rs
    q1, q2 = slope * w00, slope * w01
    d1, d2 = (w00 - w10) / rwc, (w01 - w11) / rwc
    steps = zip(np.asarray(voltage, dtype=float)[: max(n - 1, 0)].tolist(), (0.5 * slope / cw * h_arr).tolist(),
                e1.tolist(), e2.tolist(), ((e1 - 1.0) / lam1 * g[0]).tolist(), ((e2 - 1.0) / lam2 * g[1]).tolist(),
                strict=True)
    limit = math.inf if current_limit is None else float(current_limit)
    zs1, zs2, cur = [z1], [z2], []
    for vk, half, a1, a2, b1, b2 in steps:
        r = r0 + q1 * z1 + q2 * z2
        i = vk / r
        if i > limit:
            i = limit
        cur.append(i)
        r_mid = r + half * (i * i * r - d1 * z1 - d2 * z2)
        i_mid = vk / r_mid
        if i_mid > limit:
            i_mid = limit
        p = i_mid * i_mid * r_mid
        z1 = a1 * z1 + b1 * p
        z2 = a2 * z2 + b2 * p
        zs1.append(z1)
        zs2.append(z2)
    if n:
        i = float(voltage[n - 1]) / (r0 + q1 * z1 + q2 * z2)
        cur.append(min(i, limit))
    else:
        zs1, zs2 = [], []
    m1, m2 = np.asarray(zs1), np.asarray(zs2)
    tws, tcs = ta + w00 * m1 + w01 * m2, ta + w10 * m1 + w11 * m2
    return StallRun(t_arr, np.asarray(cur), np.asarray(tws), np.asarray(tcs))


def time_to_temperature(
    resistance: float, thermal: ThermalModel, voltage: float, limit: float = WINDING_LIMIT, *,
    winding: float | None = None, case: float | None = None,
) -> float:
    """Time [s] a motor stalled at ``voltage`` takes for its winding to reach ``limit`` [°C] (inf: never).

    Parameters
    ----------
    resistance
        R₂₅ [Ω].
    thermal
        The thermal network.
    voltage
        Terminal voltage held [V].
    limit
        Winding temperature [°C].
    winding, case
        Initial temperatures [°C] (default: ambient).
    """
    tw0 = thermal.ambient_temperature if winding is None else winding
    if tw0 >= limit:
        return 0.0
    steady = steady_stall_temperature(resistance, thermal, voltage)
    if steady < limit:
        return math.inf
    fast, slow = thermal.time_constants
    h = fast / 20.0
    horizon = 20.0 * slow
    t0, tw, tc = 0.0, tw0, (tw0 if case is None else case)
    while t0 < horizon:
        n = 400
        times = t0 + h * np.arange(n + 1)
        run = stall_response(resistance, thermal, times, np.full(n + 1, float(voltage)), winding=tw, case=tc)
        hit = np.flatnonzero(run.winding_temperature >= limit)
        if hit.size:
            k = int(hit[0])
            if k == 0:
                return t0
            a, b = run.winding_temperature[k - 1], run.winding_temperature[k]
            return float(times[k - 1] + (limit - a) / (b - a) * h)
        t0, tw, tc = float(times[-1]), float(run.winding_temperature[-1]), float(run.case_temperature[-1])
        h *= 2.0
    return math.inf


def steady_stall_temperature(resistance: float, thermal: ThermalModel, voltage: float) -> float:
    """Winding temperature [°C] a stall at ``voltage`` settles at (inf if the copper runs away).

    Notes
    -----
    θ = V²·R_th/(R₂₅·(1 + α·(T_a + θ − 25))) with R_th = R_wc + R_ca: a quadratic in the rise θ,
    α·θ² + c·θ − V²·R_th/R₂₅ = 0 with c = 1 + α·(T_a − 25).
    """
    r_th = thermal.winding_to_case + thermal.case_to_ambient
    alpha = thermal.resistance_coefficient
    c = 1.0 + alpha * (thermal.ambient_temperature - REFERENCE_TEMPERATURE)
    q = voltage**2 * r_th / resistance
    theta = q / c if alpha == 0 else (-c + math.sqrt(c * c + 4 * alpha * q)) / (2 * alpha)
    return thermal.ambient_temperature + theta


def continuous_current(resistance: float, thermal: ThermalModel, rise: float = 100.0) -> tuple[float, float]:
    """The stall current [A] (and its voltage [V]) a motor holds indefinitely with its winding ``rise`` K
    above ambient: I = √(ΔT/(R(T_a + ΔT)·(R_wc + R_ca)))."""
    r_hot = resistance * thermal.resistance_factor(thermal.ambient_temperature + rise)
    current = math.sqrt(rise / (r_hot * (thermal.winding_to_case + thermal.case_to_ambient)))
    return current, current * r_hot


#: A log whose I²·R energy would warm the winding by more than this [K] is warned about.
HEAT_WARNING_RISE = 10.0
#: The network used for a log when the motor's own is not known: the catalogue's estimate for the
#: 550-size motors of FTC gearmotors (``data/thermal.toml``, family ``can550``).
DEFAULT_NETWORK = ThermalModel(winding_to_case=0.9, case_to_ambient=4.8, winding_capacity=20.0, case_capacity=48.0)


#: Most bins :func:`log_rise` moves through the network (at 0.1 s, logs up to 1.4 h; longer ones get wider bins).
LOG_RISE_BINS = 50_000


def log_rise(time: np.ndarray, current: np.ndarray, resistance: float,
             thermal: ThermalModel = DEFAULT_NETWORK) -> tuple[float, float]:
    """The I²·R energy [J] of a log and the largest rise of the winding [K] it causes in ``thermal``.

    The heat R·i² is averaged over bins of 0.1 s (or the samples, when sparser; wider bins beyond
    :data:`LOG_RISE_BINS`) and moved through the network exactly; R is held (the rise it would add
    is second order for a warning).
    """
    t = np.asarray(time, dtype=float)
    i = np.asarray(current, dtype=float)
    ok = np.isfinite(t) & np.isfinite(i)
    t, i = t[ok], i[ok]
    if t.size < 2 or not (math.isfinite(resistance) and resistance > 0):
        return 0.0, 0.0
    order = np.argsort(t, kind="stable")
    t, i = t[order], i[order]
    dt = np.clip(np.diff(t), 0.0, None)
    heat = resistance * 0.5 * (i[1:] ** 2 + i[:-1] ** 2) * dt
    # Bins of 0.1 s, wider on a log longer than LOG_RISE_BINS of them (a 2 M-row table of 18 s
    # operating points spans 10 h: 360 M bins took 24 GB): the work stays bounded.
    width = max(0.1, float(t[-1] - t[0]) / LOG_RISE_BINS)
    edges = np.arange(t[0], t[-1] + width, width)
    energy_bins = np.bincount(np.clip(np.searchsorted(edges, t[:-1], side="right") - 1, 0, None),
                              weights=heat, minlength=edges.size)
    tw = tc = thermal.ambient_temperature
    peak = tw
    for e in energy_bins.tolist():
        tw, tc = thermal.step(tw, tc, e / width, width)
        peak = max(peak, tw)
    return float(np.sum(heat)), float(peak - thermal.ambient_temperature)


def heat_warning(time: np.ndarray, current: np.ndarray, resistance: float, *, what: str = "this log",
                 resistance_note: str = "", thermal: ThermalModel = DEFAULT_NETWORK) -> str | None:
    """A warning when a log's I²·R heat warms the winding by more than :data:`HEAT_WARNING_RISE` K, else None."""
    energy, rise = log_rise(time, current, resistance, thermal)
    if rise <= HEAT_WARNING_RISE:
        return None
    note = f" ({resistance_note})" if resistance_note else ""
    return (f"{what} put {energy:.3g} J of I²·R heat into the winding (R = {resistance:.3g} Ω{note}): about "
            f"{rise:.0f} K of rise for a winding of {thermal.winding_capacity:g} J/K behind "
            f"{thermal.winding_to_case:g} K/W (a 550-size FTC motor's estimate), so R rose by about "
            f"{100 * COPPER_COEFFICIENT * rise:.0f} % during "
            "it and the fit averages over a warming winding; let the motor cool between runs, or measure the "
            "heating with a stall run (analyze stall)")
