"""Simulated units of a catalogue motor: each unit's true parameters drawn around the nominal ones.

Seed 1's "Final Calculated Parameters" lists three units (A, B, C) of each motor: their back-EMF
constants agree within a few per cent (AM 40: 0.705-0.763 V·s), their inductances within about
10 % (AM 3.7: 679-880 µH), while friction differs by factors (AM 40 b: 0.018-0.56) and resistance
scatters widely. The spreads below follow that picture; each parameter is drawn log-normally
(never negative), deterministically from the unit seed and the motor's key.
"""

from __future__ import annotations

import math
import zlib
from dataclasses import asdict, dataclass, replace
from typing import Any, Protocol

import numpy as np

from motorlab.errors import OptionError
from motorlab.gearbox import Gearbox
from motorlab.model import PARAMETER_NAMES, MotorParams


class _HasNominal(Protocol):
    @property
    def key(self) -> str: ...

    def nominal_params(self) -> MotorParams: ...


@dataclass(frozen=True)
class UnitSpread:
    """Log-normal spreads (σ of ln x) of the unit-to-unit variation of each parameter.

    Parameters
    ----------
    K, R, L, J, b, Tf
        σ of the natural logarithm [-] (0.03 ≈ ±3 %). Draws are clipped at ±3 σ.
    """

    K: float = 0.03
    R: float = 0.10
    L: float = 0.08
    J: float = 0.05
    # Seed 1's sibling units give σ(ln b) ≈ 0.12 (AM 20: 0.0022/0.0025/0.0028; AM 3.7 and Matrix alike),
    # which includes their measurement scatter; the units' own spread is taken a little narrower.
    b: float = 0.10
    Tf: float = 0.10

    def __post_init__(self) -> None:
        for name in PARAMETER_NAMES:
            if not getattr(self, name) >= 0:
                raise OptionError(f"unit spread of {name} must not be negative")

    def to_dict(self) -> dict[str, float]:
        """Plain dict for ``truth.json``."""
        return asdict(self)


def unit_name(unit_seed: int) -> str:
    """The unit's letter name: 0 -> "A", 1 -> "B", …, 25 -> "Z", 26 -> "AA" (as the seed labels units)."""
    if unit_seed < 0:
        raise OptionError(f"unit seed must not be negative, got {unit_seed}")
    name = ""
    n = unit_seed + 1
    while n:
        n, r = divmod(n - 1, 26)
        name = chr(ord("A") + r) + name
    return name


def _rng(key: str, unit_seed: int, stream: int) -> np.random.Generator:
    # crc32 of the key (not hash(), which is salted per process) keeps the draw reproducible.
    return np.random.default_rng([unit_seed, zlib.crc32(key.encode()), stream])


def draw_unit(motor: _HasNominal, unit_seed: int, *, spread: UnitSpread | None = None) -> MotorParams:
    """True parameters of one unit of ``motor``, drawn around its nominal parameters.

    Parameters
    ----------
    motor
        A catalogue :class:`~motorlab.catalog.Motor` (anything with ``key`` and ``nominal_params()``).
    unit_seed
        Which unit (≥ 0): 0 is unit "A", 1 is "B", … The draw depends only on the seed and the
        motor's key.
    spread
        Spreads of the parameters (default :class:`UnitSpread`).

    Returns
    -------
    MotorParams
        K, R, L, J, b, Tf of this unit at the output (encoder) shaft.

    Raises
    ------
    OptionError
        For a negative seed.

    Notes
    -----
    x_unit = x_nominal·exp(σ_x·z), z ~ N(0, 1) clipped at ±3.

    References
    ----------
    Seed 1, "Final Calculated Parameters" (units A, B, C of each motor).
    """
    if unit_seed < 0:
        raise OptionError(f"unit seed must not be negative, got {unit_seed}")
    spread = spread or UnitSpread()
    nominal = motor.nominal_params()
    z = np.clip(_rng(motor.key, unit_seed, 0).standard_normal(len(PARAMETER_NAMES)), -3.0, 3.0)
    values = {
        name: getattr(nominal, name) * math.exp(getattr(spread, name) * float(zk))
        for name, zk in zip(PARAMETER_NAMES, z, strict=True)
    }
    return MotorParams(**values)


@dataclass(frozen=True)
class Commutator:
    """How the brushes and commutator make the LCR readings depend on shaft position.

    Parameters
    ----------
    inductance_variation
        Relative amplitude of L(θ) [-]: the coils in circuit change as the brushes pass the
        segments (seed 1's L readings of one unit: 641-733 µH, about ±6 %).
    resistance_variation
        Relative amplitude of the winding resistance between the brushes [-].
    contact_median
        Median brush contact resistance [Ω].
    contact_sigma
        σ of ln(contact resistance) [-].
    poor_contact_probability
        Chance that a position gives a poor brush contact [-].
    poor_contact_range
        A poor contact adds R·U(lo, hi) [-] (seed 1's DCR column: 1.38-3.65 Ω around R ≈ 1.9 Ω).
    ac_resistance_factor
        R_ac/R_dc of the winding at the test frequency [-] (iron and eddy losses; seed 1's Q-derived
        resistances average 2.5 Ω against 1.9 Ω DCR).
    """

    inductance_variation: float = 0.06
    resistance_variation: float = 0.05
    contact_median: float = 0.03
    contact_sigma: float = 0.8
    poor_contact_probability: float = 0.2
    poor_contact_range: tuple[float, float] = (0.3, 0.9)
    ac_resistance_factor: float = 1.25

    @property
    def mean_good_contact(self) -> float:
        """Mean brush contact resistance of a good contact [Ω] (log-normal mean median·exp(σ²/2))."""
        return self.contact_median * math.exp(0.5 * self.contact_sigma**2)

    def expected_ac_resistance(self, params: MotorParams) -> float:
        """Mean R_ac = k_ac·R_w + R_c at good contacts [Ω]: what 2πfL/Q finds with poor contacts set aside."""
        winding_mean = params.R - min(self.mean_good_contact, 0.5 * params.R)
        return self.ac_resistance_factor * winding_mean + self.mean_good_contact

    def positions(
        self, params: MotorParams, count: int, rng: np.random.Generator
    ) -> dict[str, np.ndarray]:
        """True series L [H], R_ac [Ω], DCR [Ω] and contact resistance [Ω] at ``count`` random positions.

        Notes
        -----
        L(φ) = L·(1 + a_L·cos φ), R_w(φ) = (R − R̄_c)·(1 + a_R·cos(φ + π/3)), DCR = R_w + R_c,
        R_ac = k_ac·R_w + R_c, with φ uniform (the seed turns the shaft to "random positions").
        The model's R is the terminal resistance of the running motor, brushes included, so the
        winding is R less the mean good brush contact R̄_c = median·exp(σ²/2): a DCR reading at a
        good contact is R on average, and only the poor contacts read high.
        """
        phase = rng.uniform(0.0, 2 * math.pi, count)
        inductance = params.L * (1 + self.inductance_variation * np.cos(phase))
        winding_mean = params.R - min(self.mean_good_contact, 0.5 * params.R)
        winding = winding_mean * (1 + self.resistance_variation * np.cos(phase + math.pi / 3))
        contact = self.contact_median * np.exp(self.contact_sigma * rng.standard_normal(count))
        poor = rng.random(count) < self.poor_contact_probability
        contact = contact + np.where(poor, params.R * rng.uniform(*self.poor_contact_range, count), 0.0)
        return {
            "inductance": inductance,
            "ac_resistance": self.ac_resistance_factor * winding + contact,
            "dc_resistance": winding + contact,
            "contact_resistance": contact,
            "phase": phase,
        }

    def settings(self) -> dict[str, Any]:
        """Settings for ``truth.json``."""
        out: dict[str, Any] = asdict(self)
        out["poor_contact_range"] = list(self.poor_contact_range)
        return out


#: σ of ln η between units of one gearmotor [-] (gear cutting, grease, run-in).
EFFICIENCY_SPREAD = 0.03


def draw_gearbox(key: str, nominal: Gearbox, unit_seed: int, *, spread: float = EFFICIENCY_SPREAD) -> Gearbox:
    """One unit's gearbox: the efficiency drawn log-normally around ``nominal``'s (clipped at ±3 σ, ≤ 0.99).

    Parameters
    ----------
    key
        The motor's catalogue key (the draw depends only on it and the seed).
    nominal
        The catalogue gearbox (:meth:`motorlab.catalog.Motor.gearbox`).
    unit_seed
        Which unit (≥ 0).
    spread
        σ of ln η [-].
    """
    if unit_seed < 0:
        raise OptionError(f"unit seed must not be negative, got {unit_seed}")
    z = float(np.clip(_rng(key, unit_seed, 1).standard_normal(), -3.0, 3.0))
    eta = min(nominal.efficiency * math.exp(spread * z), 0.99)
    return replace(nominal, efficiency=eta, back_efficiency=None)
