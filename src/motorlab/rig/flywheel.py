"""The dynamometer's flywheel: a steel disc behind a 25:1 step-up gearbox.

Seed 1 ("First Experiment") sizes the flywheel: J = ½·m·r² = ½·π·r⁴·ρ·h for a uniform disc, and
proposes a "practical sized" steel disc of r = 0.075 m, h = 0.05 m (ρ = 7850 kg/m³). The seed
writes 0.0124 kg·m² for it, but its own formula gives ½·π·0.075⁴·7850·0.05 = 0.0195 kg·m²
(m = 6.94 kg): the seed's figure is an arithmetic slip. The default :class:`Disc` is the seed's
disc with the correct inertia. The gearbox ("Machining Process") is 25:1 "with the fastest shaft
on the flywheel", so seen from the motor's output shaft (whose encoder is counted) the disc weighs
J·N² and the gearbox's friction is reflected too.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from motorlab.errors import OptionError
from motorlab.model import MotorParams
from motorlab.model.load import MATERIALS, disc_inertia

#: Densities [kg/m³] of disc materials (the one table, :data:`motorlab.model.load.MATERIALS`).
DENSITIES = MATERIALS


@dataclass(frozen=True)
class Disc:
    """A uniform disc turning about its axis.

    Parameters
    ----------
    radius
        Radius r [m].
    thickness
        Thickness h [m].
    material
        A key of :data:`DENSITIES` (``"steel"``) or a density [kg/m³].
    """

    radius: float = 0.075
    thickness: float = 0.05
    material: str | float = "steel"

    def __post_init__(self) -> None:
        if not (self.radius > 0 and self.thickness > 0):
            raise OptionError(f"disc radius and thickness must be positive, got {self.radius}, {self.thickness}")
        if isinstance(self.material, str) and self.material.lower() not in DENSITIES:
            raise OptionError(f"unknown disc material {self.material!r}; known: {', '.join(DENSITIES)}")
        if not isinstance(self.material, str) and not self.material > 0:
            raise OptionError(f"disc density must be positive, got {self.material}")

    @property
    def density(self) -> float:
        """ρ [kg/m³]."""
        if isinstance(self.material, str):
            return DENSITIES[self.material.lower()]
        return float(self.material)

    @property
    def mass(self) -> float:
        """m = π·r²·h·ρ [kg]."""
        return math.pi * self.radius**2 * self.thickness * self.density

    @property
    def inertia(self) -> float:
        """J = ½·m·r² = ½·π·r⁴·ρ·h [kg·m²] (seed 1, "First Experiment")."""
        return disc_inertia(self.radius, self.thickness, self.density)


@dataclass(frozen=True)
class Flywheel:
    """Disc, step-up gearbox and their friction, as attached to the motor's output shaft.

    Parameters
    ----------
    disc
        The disc.
    ratio
        Flywheel speed / motor output speed N [-] (25 in seed 1).
    viscous_friction
        Viscous friction at the flywheel shaft [N·m·s/rad] (bearings, oil, air), reflected as b·N².
    coulomb_friction
        Coulomb friction at the flywheel shaft [N·m] (gear mesh, seals), reflected as Tf·N.
    gear_inertia
        Inertia of the gears and axle at the flywheel shaft [kg·m²], added to the disc's.

    Notes
    -----
    With the flywheel turning N times faster than the motor output shaft, kinetic energy
    ½·J·(N·ω)² and power b·(N·ω)² reflect as J·N² and b·N², while a constant friction torque Tf
    dissipates Tf·N·ω and reflects as Tf·N. The defaults make the seed's spin-down last about
    a minute (γ = b/J ≈ 1/40 s) as in its "First Motor on a Gearbox Test".
    """

    disc: Disc = field(default_factory=Disc)
    ratio: float = 25.0
    viscous_friction: float = 2.5e-4
    coulomb_friction: float = 4e-3
    gear_inertia: float = 2e-5

    def __post_init__(self) -> None:
        if not self.ratio > 0:
            raise OptionError(f"gear ratio must be positive, got {self.ratio}")
        if self.viscous_friction < 0 or self.coulomb_friction < 0 or self.gear_inertia < 0:
            raise OptionError("flywheel friction and gear inertia must not be negative")

    @property
    def inertia(self) -> float:
        """Inertia at the flywheel shaft [kg·m²] (disc + gears)."""
        return self.disc.inertia + self.gear_inertia

    @property
    def reflected_inertia(self) -> float:
        """J·N² at the motor output shaft [kg·m²]."""
        return self.inertia * self.ratio**2

    @property
    def reflected_viscous_friction(self) -> float:
        """b·N² at the motor output shaft [N·m·s/rad]."""
        return self.viscous_friction * self.ratio**2

    @property
    def reflected_coulomb_friction(self) -> float:
        """Tf·N at the motor output shaft [N·m]."""
        return self.coulomb_friction * self.ratio

    def attach(self, params: MotorParams) -> MotorParams:
        """The parameters at the encoder shaft with this flywheel attached (J, b, Tf totals)."""
        return params.scaled(
            J=params.J + self.reflected_inertia,
            b=params.b + self.reflected_viscous_friction,
            Tf=params.Tf + self.reflected_coulomb_friction,
        )

    def settings(self) -> dict[str, Any]:
        """Settings and derived figures for ``truth.json``."""
        return {
            "disc": {
                "radius": self.disc.radius,
                "thickness": self.disc.thickness,
                "material": self.disc.material,
                "density": self.disc.density,
                "mass": self.disc.mass,
                "J": self.disc.inertia,
            },
            "ratio": self.ratio,
            "gear_inertia": self.gear_inertia,
            "viscous_friction": self.viscous_friction,
            "coulomb_friction": self.coulomb_friction,
            "J_reflected": self.reflected_inertia,
            "b_reflected": self.reflected_viscous_friction,
            "Tf_reflected": self.reflected_coulomb_friction,
        }
