"""The robot link: pull an FTC robot's logs over Wi-Fi, record live runs, write gains back (docs/robot.md).

Everything here talks to one address only, the robot's (``host``; a Control Hub is ``192.168.43.1``, a
phone robot controller ``192.168.49.1``), with a time limit on every request:

* :mod:`motorlab.robot.http` and :mod:`motorlab.robot.pull`: the robot controller's web server (port
  8080): Road Runner's tuning files and FlightRecorder logs (road-runner-ftc ``FileServing.kt``) and the
  logs of motorlab's own OpModes (``ftc/``, ``MotorlabLogFiles.java``);
* :mod:`motorlab.robot.dashboard`: FTC Dashboard's WebSocket (port 8000; acmerobotics/ftc-dashboard);
* :mod:`motorlab.robot.record`: init, start, record and stop an OpMode through the Dashboard;
* :mod:`motorlab.robot.config`: the Dashboard's ``@Config`` tree: find a target's fields, write only
  those leaves, read them back, and restore the old values;
* :mod:`motorlab.robot.emulator`: an emulated robot on 127.0.0.1, for tests and demos.

Nothing here starts an OpMode unless asked in so many words (:func:`motorlab.robot.record.record`).
"""

from __future__ import annotations

from motorlab.errors import MotorlabError

#: The Control Hub's address on its own Wi-Fi network (a phone robot controller: 192.168.49.1).
DEFAULT_HOST = "192.168.43.1"
#: The robot controller's web server (Road Runner's routes, motorlab's log handler).
DEFAULT_HTTP_PORT = 8080
#: FTC Dashboard's WebSocket server (``new NanoWSD(8000)`` in ``FtcDashboard.java``).
DEFAULT_DASHBOARD_PORT = 8000


class RobotLinkError(MotorlabError):
    """The robot could not be reached, or did not answer as expected: one line saying what to do."""
