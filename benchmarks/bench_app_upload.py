"""The app through its upload limit (issue 25): time and peak memory of the server and its worker.

Starts ``motorlab ui --no-browser`` on a free port of 127.0.0.1 (a fresh Python process, as a user
starts it), writes a Rigol DS1054Z waveform export of one encoder channel as large as the upload limit
allows (``motorlab.ui.uploads.MAX_UPLOAD``, 200 MiB, with the form around it), and sends it to
``/api/analyze/free-spinup`` as the page does (a multipart form with the file and the options),
streaming the body from the file. While the request runs, ``/proc`` is read every 50 ms for the peak
resident memory (VmHWM) of the server and of every process under it (the warm workers, one of which
runs the command).

    python benchmarks/bench_app_upload.py [SAMPLES]     # default: as many as fit in the limit

prints the export's size and samples, the request's wall time and status, the server's and the
busiest worker's peak MiB, and the answer's J. The figures are in docs/formats.md ("Large files").
"""

from __future__ import annotations

import http.client
import json
import os
import socket
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Iterator
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_scale import CPR, _rigol
from motorlab.ui.uploads import MAX_UPLOAD

BOUNDARY = "motorlab-bench-boundary"
#: Bytes a sample takes in the export (``k,V,`` rows) at 12 M samples, measured; the form adds < 1 kB.
BYTES_PER_SAMPLE = 16.5


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _hwm(pid: int) -> float:
    """VmHWM of ``pid`` [MiB] (0 when it is gone)."""
    try:
        with open(f"/proc/{pid}/status") as handle:
            for line in handle:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024
    except OSError:
        pass
    return 0.0


def _cpu(pid: int) -> float:
    """User + system CPU seconds of ``pid`` so far (0 when it is gone)."""
    try:
        with open(f"/proc/{pid}/stat") as handle:
            fields = handle.read().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    except (OSError, IndexError, ValueError):
        return 0.0


def _descendants(pid: int) -> list[int]:
    out, todo = [], [pid]
    while todo:
        parent = todo.pop()
        try:
            with open(f"/proc/{parent}/task/{parent}/children") as handle:
                kids = [int(k) for k in handle.read().split()]
        except OSError:
            kids = []
        out += kids
        todo += kids
    return out


class Watch(threading.Thread):
    """Peak VmHWM of the server and of the processes under it, sampled every 50 ms."""

    def __init__(self, pid: int) -> None:
        super().__init__(daemon=True)
        self.pid, self.server, self.workers, self.done = pid, 0.0, {}, threading.Event()
        self.cpu: dict[int, float] = {}
        self.start_cpu = _cpu(pid)

    def run(self) -> None:
        while not self.done.is_set():
            self.server = max(self.server, _hwm(self.pid))
            self.cpu[self.pid] = _cpu(self.pid) - self.start_cpu
            for child in _descendants(self.pid):
                self.workers[child] = max(self.workers.get(child, 0.0), _hwm(child))
                self.cpu[child] = max(self.cpu.get(child, 0.0), _cpu(child))
            time.sleep(0.05)


def _body(path: Path, fields: dict[str, str]) -> tuple[list[bytes | Path], int]:
    parts: list[bytes | Path] = []
    for name, value in fields.items():
        parts.append(f'--{BOUNDARY}\r\nContent-Disposition: form-data; name="{name}"\r\n\r\n{value}\r\n'.encode())
    parts.append(f'--{BOUNDARY}\r\nContent-Disposition: form-data; name="file"; filename="{path.name}"\r\n'
                 "Content-Type: text/csv\r\n\r\n".encode())
    parts += [path, f"\r\n--{BOUNDARY}--\r\n".encode()]
    size = sum(p.stat().st_size if isinstance(p, Path) else len(p) for p in parts)
    return parts, size


def _stream(parts: list[bytes | Path]) -> Iterator[bytes]:
    for part in parts:
        if isinstance(part, Path):
            with open(part, "rb") as handle:
                while chunk := handle.read(1 << 20):
                    yield chunk
        else:
            yield part


def main(argv: list[str]) -> int:
    samples = int(float(argv[0])) if argv else int((MAX_UPLOAD - 4096) / BYTES_PER_SAMPLE)
    port = _free_port()
    with tempfile.TemporaryDirectory(prefix="motorlab-bench-app-") as tmp:
        export = Path(tmp) / "waveform.csv"
        _rigol(export, samples)
        fields = {"K": "0.7", "current": "0.5 A", "cpr": str(CPR)}
        parts, size = _body(export, fields)
        if size > MAX_UPLOAD:  # trim to the limit: whole rows off the end (the export stops earlier)
            with open(export, "r+b") as handle:
                handle.seek(export.stat().st_size - (size - MAX_UPLOAD) - 64)
                tail = handle.read(64)
                handle.truncate(handle.tell() - 64 + tail.rindex(b"\n") + 1)
            parts, size = _body(export, fields)
            with open(export, "rb") as handle:
                samples = sum(chunk.count(b"\n") for chunk in iter(lambda: handle.read(1 << 20), b"")) - 2
        server = subprocess.Popen([sys.executable, "-m", "motorlab", "ui", "--no-browser", "--port", str(port)],
                                  stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                  env={**os.environ, "MPLBACKEND": "Agg"})
        try:
            for _ in range(600):
                try:
                    socket.create_connection(("127.0.0.1", port), timeout=0.2).close()
                    break
                except OSError:
                    time.sleep(0.1)
            time.sleep(3.0)  # the warm workers import
            watch = Watch(server.pid)
            watch.start()
            start = time.perf_counter()
            conn = http.client.HTTPConnection("127.0.0.1", port, timeout=3600)
            conn.request("POST", "/api/analyze/free-spinup", body=_stream(parts),
                         headers={"Content-Type": f"multipart/form-data; boundary={BOUNDARY}",
                                  "Content-Length": str(size)})
            response = conn.getresponse()
            answer = response.read()
            wall = time.perf_counter() - start
            time.sleep(0.2)
            watch.done.set()
            watch.join()
        finally:
            server.terminate()
            server.wait(30)
    try:
        doc = json.loads(answer)
        what = f"J = {doc['parameters']['J']['value']:.4g} kg·m²" if response.status == 200 else doc.get("error")
    except (ValueError, KeyError, TypeError):
        what = answer[:200].decode("utf-8", "replace")
    busiest = max(watch.workers, key=lambda pid: watch.cpu.get(pid, 0.0), default=None)
    worker_peak = watch.workers.get(busiest, 0.0) if busiest else 0.0
    worker_cpu = watch.cpu.get(busiest, 0.0) if busiest else 0.0
    print(f"upload {size / 2**20:.1f} MiB ({samples / 1e6:.2f} M samples) of a {MAX_UPLOAD / 2**20:.0f} MiB limit")
    print(f"status {response.status} in {wall:.1f} s wall; server {watch.cpu.get(server.pid, 0.0):.1f} s CPU, "
          f"peak {watch.server:.0f} MiB; the worker that ran it {worker_cpu:.1f} s CPU (imports included), "
          f"peak {worker_peak:.0f} MiB ({len(watch.workers)} processes under the server); {what}")
    return 0 if response.status == 200 else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
