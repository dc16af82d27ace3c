"""motorlab: characterize brushed DC gearmotors from measurements.

The library API, for notebooks and scripts::

    from motorlab.model import MotorParams
    from motorlab.simulate import simulate, VoltageDrive
    from motorlab.catalog import Motor
    from motorlab import io, analyses

Everything inside is SI; see ``docs/glossary.md``.
"""

__version__ = "0.1.0"
