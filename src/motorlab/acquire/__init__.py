"""Acquisition from real instruments: the LCR meter, bench supplies and oscilloscopes.

- :mod:`motorlab.acquire.es51919` decodes the DER EE DE-5000's packets (Cyrustek ES51919 chip);
  :func:`motorlab.acquire.lcr.acquire_lcr` reads the meter over pyserial into the file
  ``motorlab analyze lcr`` reads; :mod:`motorlab.acquire.emulator` serves packets on a socket.
- :mod:`motorlab.acquire.scpi` drives a bench supply (Korad KA3005P, Rigol DP800) and a scope
  (Rigol DS1000Z) through PyVISA; :mod:`motorlab.acquire.bench` runs the seeds' bench experiments
  with them behind the same interface as the virtual rig.
"""

from motorlab.acquire.errors import InstrumentError
from motorlab.acquire.lcr import LCRReading, acquire_lcr

__all__ = ["InstrumentError", "LCRReading", "acquire_lcr"]
