"""The load a dynamometer's motor drives: flywheel discs, their materials and inertia.

Pure physics (the standard library and motorlab.errors only), so that the rig design (:mod:`motorlab.rig.plan`),
the virtual rig's flywheel, the session file, the experiments' options and the analyses share one table.
"""

from __future__ import annotations

import math

from motorlab.errors import OptionError

#: Densities of common flywheel materials [kg/m³] (engineering handbook values; seed 1 uses 7850 for
#: steel, seed 2 2600 for its aluminium wheel). The one table every module uses.
MATERIALS: dict[str, float] = {
    "steel": 7850.0,
    "stainless steel": 8000.0,
    "cast iron": 7200.0,
    "aluminium": 2700.0,
    "aluminum": 2700.0,
    "brass": 8500.0,
    "copper": 8960.0,
    "acrylic": 1180.0,
    "pla": 1240.0,
    "abs": 1050.0,
    "plywood": 600.0,
    "hdpe": 960.0,
}


def disc_inertia(radius: float, thickness: float, density: float, *, ratio: float = 1.0) -> float:
    """Moment of inertia of a uniform solid disc about its axis, reflected through a gear ratio.

    Parameters
    ----------
    radius
        Disc radius r [m].
    thickness
        Disc thickness h [m].
    density
        Material density ρ [kg/m³].
    ratio
        Disc speed / speed of the shaft the inertia is wanted at, N (25 for the seed's step-up
        gearbox, seen from the encoder shaft) [-].

    Returns
    -------
    float
        J = ½·m·r² = ½·π·r⁴·ρ·h at the disc, times N² at the other shaft [kg·m²] (the gears and the
        motor's own armature not included).

    References
    ----------
    Seed 1, "First Experiment": r = 0.075 m, h = 0.05 m of steel gives 0.0195 kg·m² (the seed writes
    0.0124, which is r⁴·ρ·h without the ½·π of its own formula).
    """
    require_positive(radius=radius, thickness=thickness, density=density, ratio=ratio)
    r2 = radius * radius  # products, not powers: float ** raises OverflowError where * gives inf
    return 0.5 * math.pi * r2 * r2 * density * thickness * ratio * ratio


def require_positive(**values: float) -> None:
    """Refuse, naming it in words, any value that is not a finite positive number (OptionError)."""
    for name, value in values.items():
        if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
            raise OptionError(f"{name.replace('_', ' ')} must be a positive number, got {value!r}")
