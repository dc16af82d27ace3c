"""The test browser leaves nothing running: every process of it ends when its driver quits (Debian's
``/usr/bin/chromium-headless-shell`` is a script that runs the browser without ``exec``: quitting ended the script
and left the browser and its renderers behind, one set per test process, hundreds on a machine after a day)."""

from __future__ import annotations

import time
from pathlib import Path

import pytest
import ui_browser as browser


def _running(pid: int) -> bool:
    """Alive and not a zombie waiting to be reaped."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


@browser.needs_browser
@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads the process table from /proc")
def test_quitting_the_browser_ends_every_process_of_it() -> None:
    driver = browser.make_driver()
    driver.get("data:text/html,<p>motorlab</p>")
    processes = browser.process_tree(driver.service.process.pid)[1:]  # the driver's descendants
    assert len(processes) >= 2, "the browser's processes were not found"  # the browser and its renderer at least
    driver.quit()
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline and any(_running(p) for p in processes):
        time.sleep(0.05)
    left = sorted(p for p in processes if _running(p))
    assert not left, f"processes of the browser still running after quit: {left}"
