"""The recording type every reader returns: SI arrays plus metadata."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from motorlab.errors import LogFormatError

#: Canonical signal names and their SI units. Readers convert to these; analyses ask for these.
SIGNALS: dict[str, str] = {
    "position": "rad",  # encoder shaft angle
    "counts": "count",  # raw encoder counts (kept beside position when the log has them)
    "velocity": "rad/s",
    "voltage": "V",  # applied / bus / terminal voltage
    "current": "A",
    "command": "V",  # commanded input (function generator, amplifier input)
    "mass": "kg",  # scale reading
    "torque": "N*m",
    "inductance": "H",
    "quality_factor": "1",
    "dc_resistance": "ohm",
    "frequency": "Hz",
    "battery": "V",
    "speed": "rad/s",  # optical tachometer reading
    "tach_voltage": "V",
    # a dynamometer's export (worded headers, motorlab.io.headers)
    "output_power": "W",  # mechanical power at the shaft
    "input_power": "W",  # electrical power supplied
    "power_dissipation": "W",  # input − output: heat in the motor
    "efficiency": "1",  # a fraction (a column in % is divided by 100)
    "temperature": "K",  # a thermometer's reading (a column in °C is read with its offset)
    "winding_temperature": "K",  # a winding's temperature (simulate stall writes °C)
    "case_temperature": "K",
}


@dataclass
class Recording:
    """One measured run (or a set of rows of one experiment).

    Attributes
    ----------
    time
        Sample times [s] (a row index for tables without time, such as LCR readings).
    signals
        Arrays by canonical name (see :data:`SIGNALS`), all in SI and of the length of ``time``.
    metadata
        Free-form facts from the file: ``format``, ``cpr``, units as written, test name ...
    source
        Path(s) of the file(s) read, joined with ``" + "`` when a run spans several files.
    lines
        1-based line number in the source of each sample (for error messages), if known.
    segments
        Named sub-runs (``{"slow-forward": (start, stop)}``) when one file holds several tests.
    """

    time: np.ndarray
    signals: dict[str, np.ndarray]
    metadata: dict[str, Any] = field(default_factory=dict)
    source: str = ""
    lines: np.ndarray | None = None
    segments: dict[str, tuple[int, int]] = field(default_factory=dict)

    def __repr__(self) -> str:
        """A short summary (the arrays are not printed)."""
        span = f"{self.time[0]:.6g}..{self.time[-1]:.6g} s" if len(self.time) else "empty"
        source = f", source={self.source!r}" if self.source else ""
        return f"Recording({len(self.time)} rows, {span}, signals={sorted(self.signals)}{source})"

    def __post_init__(self) -> None:
        self.time = np.asarray(self.time, dtype=float)
        for name, values in self.signals.items():
            arr = np.asarray(values, dtype=float)
            if arr.shape != self.time.shape:
                raise ValueError(f"signal {name!r} has {arr.size} samples, time has {self.time.size}")
            self.signals[name] = arr

    def __len__(self) -> int:
        return int(self.time.size)

    def __contains__(self, name: object) -> bool:
        return name in self.signals

    def __getitem__(self, name: str) -> np.ndarray:
        return self.require(name)

    def has(self, *names: str) -> bool:
        """True when every named signal is present."""
        return all(n in self.signals for n in names)

    def require(self, name: str) -> np.ndarray:
        """The named signal, or a :class:`LogFormatError` naming the file and what is missing."""
        try:
            return self.signals[name]
        except KeyError:
            have = ", ".join(sorted(self.signals)) or "none"
            hint = ""
            if self.metadata.get("format") == "csv":
                hint = f"; if a column holds it, map it with --column \"HEADER={name}\""
            lacks = self.metadata.get("lacks")  # a reader's words on how to log what its format lacks
            if isinstance(lacks, dict) and name in lacks:
                hint = f": {lacks[name]}"
            raise LogFormatError(f"this log has no {name} (it has: {have}){hint}", path=self.source or None) from None

    def line_of(self, index: int) -> int | None:
        """Source line of sample ``index`` (None if unknown)."""
        if self.lines is None or not 0 <= index < self.lines.size:
            return None
        return int(self.lines[index])

    def select(self, mask_or_slice: Any) -> Recording:
        """A new recording with only the chosen samples (metadata shared, segments dropped)."""
        idx = mask_or_slice
        return Recording(
            time=self.time[idx],
            signals={k: v[idx] for k, v in self.signals.items()},
            metadata=dict(self.metadata),
            source=self.source,
            lines=None if self.lines is None else self.lines[idx],
        )

    def split(self) -> list[Recording]:
        """One recording per named segment (or ``[self]`` when there are none)."""
        if not self.segments:
            return [self]
        parts = []
        for name, (start, stop) in self.segments.items():
            part = self.select(slice(start, stop))
            part.metadata["segment"] = name
            parts.append(part)
        return parts
