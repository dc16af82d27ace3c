"""A DE-5000 emulator: serves ES51919 packets on a localhost TCP socket (pyserial's ``socket://``).

For tests and for trying ``motorlab acquire lcr`` without a meter::

    from motorlab.acquire.emulator import DE5000Emulator, winding_stream
    with DE5000Emulator(winding_stream([2.2e-3, 2.3e-3], [8.9, 9.1])) as meter:
        acquire_lcr(meter.url, "lcr.csv", readings=2)

Each client that connects receives the whole byte stream (cut into ``chunk``-byte writes with
``interval`` seconds between them, so that reads see partial packets), then ``repeat`` over and
over (a meter left on, as for interactive runs) or, without it, silence until the emulator stops
(a meter switched off mid-run).
"""

from __future__ import annotations

import math
import socket
import threading
from collections.abc import Sequence

import numpy as np

from motorlab.acquire.es51919 import encode


def winding_stream(
    inductances: Sequence[float],
    quality_factors: Sequence[float],
    *,
    frequency: float = 1000.0,
    secondary: str = "quality_factor",
    parallel: bool = False,
    garbage: int = 0,
    overloads: int = 0,
    seed: int = 0,
) -> bytes:
    """Packets of an inductance reading each, optionally with noise bytes and "OL"/blank/"----" packets.

    Parameters
    ----------
    inductances
        L per reading [H].
    quality_factors
        Q per reading [-].
    frequency
        Test frequency [Hz].
    secondary
        What the secondary display shows: ``"quality_factor"``, ``"dissipation_factor"`` (1/Q),
        ``"phase_angle"`` (atan Q) or ``"resistance"`` (ESR ωL/Q in series, Rp = Q·ωL in parallel).
    parallel
        The meter's parallel equivalent circuit.
    garbage
        Random bytes inserted before each reading (0 for a clean stream), starting with a cut packet.
    overloads
        Non-value packets ("OL", blank, "----") inserted before each reading.
    seed
        Seed of the noise bytes.
    """
    rng = np.random.default_rng(seed)
    omega = 2 * math.pi * frequency
    out = bytearray()
    states = ("OL", "blank", "----")
    for k, (ind, q) in enumerate(zip(inductances, quality_factors, strict=True)):
        if secondary == "quality_factor":
            sec = q
        elif secondary == "dissipation_factor":
            sec = 1 / q
        elif secondary == "phase_angle":
            sec = math.atan(q)
        elif secondary == "resistance":
            sec = q * omega * ind if parallel else omega * ind / q
        else:
            raise ValueError(f"unknown secondary display {secondary!r}")
        packet = encode(("inductance", ind), (secondary, sec), frequency=frequency, parallel=parallel)
        if garbage:
            out += packet[: int(rng.integers(1, 16))]  # a packet cut short, as when the cable is plugged in
            out += rng.integers(0, 256, garbage, dtype=np.uint8).tobytes()
        for j in range(overloads):
            out += encode(("inductance", states[(k + j) % 3]), ("quality_factor", "blank"), frequency=frequency)
        out += packet
    return bytes(out)


class DE5000Emulator:
    """Serve ``stream`` to every client of a localhost TCP socket, in a background thread.

    Parameters
    ----------
    stream
        The bytes the meter sends.
    chunk
        Bytes per write (7 cuts every packet in three).
    interval
        Pause between writes [s].
    repeat
        Bytes sent again and again after ``stream`` until the emulator stops (empty: silence).
    host, port
        Address to listen on (port 0 picks a free one; see :attr:`url`).
    """

    def __init__(self, stream: bytes, *, chunk: int = 7, interval: float = 0.0005, repeat: bytes = b"",
                 host: str = "127.0.0.1", port: int = 0):
        self.stream = bytes(stream)
        self.repeat = bytes(repeat)
        self.chunk = max(1, int(chunk))
        self.interval = float(interval)
        self._server = socket.create_server((host, port))
        self._server.settimeout(0.05)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._serve, name="de5000-emulator", daemon=True)
        self._clients: list[socket.socket] = []

    @property
    def url(self) -> str:
        """``socket://host:port`` for pyserial."""
        host, port = self._server.getsockname()[:2]
        return f"socket://{host}:{port}"

    def start(self) -> DE5000Emulator:
        """Start serving."""
        self._thread.start()
        return self

    def stop(self) -> None:
        """Stop serving and close every connection."""
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(timeout=5)
        for client in self._clients:
            client.close()
        self._server.close()

    def __enter__(self) -> DE5000Emulator:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def _serve(self) -> None:
        while not self._stop.is_set():
            try:
                client, _ = self._server.accept()
            except TimeoutError:
                continue
            except OSError:
                return
            self._clients.append(client)
            threading.Thread(target=self._send, args=(client,), daemon=True).start()

    def _send(self, client: socket.socket) -> None:
        try:
            self._send_all(client, self.stream)
            while self.repeat and not self._stop.is_set():
                self._send_all(client, self.repeat)
        except OSError:  # the client went away
            return

    def _send_all(self, client: socket.socket, data: bytes) -> None:
        for start in range(0, len(data), self.chunk):
            if self._stop.is_set():
                return
            client.sendall(data[start : start + self.chunk])
            if self.interval:
                self._stop.wait(self.interval)
