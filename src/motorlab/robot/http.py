"""GET requests to the robot controller's web server, to that one address only, with time limits.

``http.client`` rather than ``urllib``: urllib follows redirects and honours ``http_proxy``, both of
which would contact another host than the robot. Here a request goes to ``host:port`` and nowhere
else, a redirect is an answer like any other (not followed), and every request has a deadline for the
whole exchange (connect, headers, body), not only per socket read.
"""

from __future__ import annotations

import http.client
import time
from dataclasses import dataclass, field

from motorlab.robot import RobotLinkError

#: Seconds for connecting and for each read; the whole request has its own deadline (``deadline``).
TIMEOUT = 5.0
#: Largest body read into memory [bytes] (FlightRecorder keeps at most 250 MB of logs in all).
MAX_BODY = 256 * 1024 * 1024
#: Where the robot is, by kind of robot controller (for messages).
WHERE = "connect this computer to the robot's Wi-Fi (Control Hub 192.168.43.1, phone 192.168.49.1) or give --host"


class RobotUnreachable(RobotLinkError):
    """No connection to the robot's web server at all (refused, no route, no answer to connect)."""


class _Connection(http.client.HTTPConnection):
    """A connection that sends the request line in UTF-8: Road Runner's ``/logs/download`` reads the query
    as it arrives, without URL-decoding (FileServing.kt:172), and NanoHTTPD decodes the request line
    with the platform's charset, UTF-8 on Android (NanoHTTPD.java:917), so a log named with a non-ASCII
    character is asked for by its UTF-8 bytes (http.client allows ASCII only)."""

    def _encode_request(self, request: str) -> bytes:
        return request.encode("utf-8")


@dataclass
class Reply:
    """One HTTP answer: status, headers (lower-case names) and the whole body."""

    status: int
    headers: dict[str, str] = field(default_factory=dict)
    body: bytes = b""


class RobotHttp:
    """The robot controller's web server at ``host:port``.

    Parameters
    ----------
    host, port
        The robot's address and the web server's port (8080 on a robot; any port for an emulator).
    timeout
        Seconds for connecting and for each read.
    deadline
        Seconds for one whole request (connect to last byte).
    """

    def __init__(self, host: str, port: int, *, timeout: float = TIMEOUT, deadline: float = 120.0) -> None:
        self.host, self.port, self.timeout, self.deadline = host, int(port), float(timeout), float(deadline)

    @property
    def address(self) -> str:
        return f"{self.host}:{self.port}"

    def get(self, path: str, *, max_bytes: int = MAX_BODY) -> Reply:
        """``GET path``; the whole body, or :class:`RobotLinkError` naming what failed and what to do."""
        start = time.monotonic()
        conn = _Connection(self.host, self.port, timeout=self.timeout)
        try:
            try:
                conn.connect()
            except ConnectionRefusedError:
                raise RobotUnreachable(f"no robot web server at {self.address} (connection refused): is the robot "
                                       f"controller app running? {WHERE}") from None
            except TimeoutError:
                raise RobotUnreachable(f"no answer from {self.address} within {self.timeout:g} s: {WHERE}") from None
            except OSError as exc:
                reason = exc.strerror or type(exc).__name__
                raise RobotUnreachable(f"cannot reach {self.address} ({reason}): {WHERE}") from None
            try:
                conn.request("GET", path, headers={"Accept-Encoding": "identity"})
                response = conn.getresponse()
            except http.client.RemoteDisconnected:
                raise RobotLinkError(f"{path} from {self.address}: the robot closed the connection without an answer "
                                     "(its handler failed)") from None
            except TimeoutError:
                raise RobotLinkError(f"{path} from {self.address}: no answer within {self.timeout:g} s") from None
            except OSError as exc:
                reason = exc.strerror or type(exc).__name__
                raise RobotLinkError(f"{path} from {self.address}: the connection broke ({reason})") from None
            headers = {k.lower(): v for k, v in response.getheaders()}
            body = self._read_body(response, path, start, max_bytes)
            return Reply(response.status, headers, body)
        finally:
            conn.close()

    def _read_body(self, response: http.client.HTTPResponse, path: str, start: float, max_bytes: int) -> bytes:
        chunks: list[bytes] = []
        size = 0
        try:
            while True:
                if time.monotonic() - start > self.deadline:
                    raise RobotLinkError(f"{path} from {self.address}: still downloading after {self.deadline:g} s; "
                                         "move closer to the robot (weak Wi-Fi) and pull again")
                chunk = response.read1(1 << 16) if hasattr(response, "read1") else response.read(1 << 16)
                if not chunk:
                    break
                size += len(chunk)
                if size > max_bytes:
                    raise RobotLinkError(f"{path} from {self.address}: larger than {max_bytes} bytes; not kept")
                chunks.append(chunk)
        except http.client.IncompleteRead:
            raise RobotLinkError(f"{path} from {self.address}: the connection dropped after {size} bytes "
                                 "(Wi-Fi lost?); nothing of it was kept: pull again") from None
        except TimeoutError:
            raise RobotLinkError(f"{path} from {self.address}: the robot stopped sending after {size} bytes "
                                 f"({self.timeout:g} s without data); nothing of it was kept: pull again") from None
        except (ConnectionError, OSError) as exc:
            reason = exc.strerror or type(exc).__name__
            raise RobotLinkError(f"{path} from {self.address}: the connection broke after {size} bytes ({reason}); "
                                 "nothing of it was kept: pull again") from None
        body = b"".join(chunks)
        expected = response.getheader("Content-Length")
        if expected is not None and expected.isdigit() and int(expected) != len(body):
            raise RobotLinkError(f"{path} from {self.address}: {len(body)} of {expected} bytes arrived; "
                                 "nothing of it was kept: pull again")
        return body
