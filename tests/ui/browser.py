"""Helpers of the browser tests: one headless Chromium, controls found as a person finds them.

A person finds a field by its label's words, a button by its text, a link by its text; so do these
helpers (never by id or CSS class). ``check_page`` asserts what every view must satisfy: no
command-line flag outside a code box, every visible field named in words, nothing wider than the
window.
"""

from __future__ import annotations

import contextlib
import functools
import os
import re
import shutil
import time
from pathlib import Path
from typing import Any

import pytest


def _headless_shell() -> str | None:
    """Debian's ``chromium-headless-shell``: the program itself. ``/usr/bin``'s is a shell script that runs it without
    ``exec``, so chromedriver's quit ended the script and left the browser running, with its renderers: one browser
    left behind by every test process (a machine that ran the suite a few dozen times had 300 of their processes)."""
    program = Path("/usr/lib/chromium/chromium-headless-shell")
    if program.is_file() and os.access(program, os.X_OK):
        return str(program)
    return shutil.which("chromium-headless-shell")


#: The browser: Debian's ``chromium-headless-shell`` where installed (Chromium's headless mode as a program of its own:
#: the same Blink, V8 and version as ``chromium``, without the browser's windowing layers; the browser tests take a
#: fifth less CPU in it, 131 s against 167 s), else ``chromium --headless``; ``MOTORLAB_TEST_CHROMIUM`` names another.
CHROMIUM = (os.environ.get("MOTORLAB_TEST_CHROMIUM") or _headless_shell()
            or shutil.which("chromium") or shutil.which("chromium-browser"))
CHROMEDRIVER = shutil.which("chromedriver")
needs_browser = pytest.mark.skipif(
    CHROMIUM is None or CHROMEDRIVER is None,
    reason="needs Debian's chromium-headless-shell (or chromium) and chromium-driver "
           "(apt-get install chromium-headless-shell chromium-driver; .ci/run does)",
)

LAPTOP, PHONE = (1366, 768), (390, 844)
FLAGS = (
    "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync", "--hide-scrollbars",
)

_FLAG_TEXT = re.compile(r"(?<![\w-])--[A-Za-z][\w-]*")

#: Terms a student does not use, outside code boxes (issue 31, point 6): the statistics' authors and symbols,
#: "prior", the reference documents ("the seeds'", "(seed 1"; a simulation's "seed 5" is the person's own
#: word), K·i, "hub" as a unit, a rate of zero written "0 1/s".
JARGON = re.compile(r"Newey|χ²|\bchi\b|chi²|chi-squared?|\bpriors?\b|\bseeds\b|\(seed \d|K·i"
                    r"|\d\s*hub\b|\bhub\s*/|/\s*hub\b|SysId mechanism, per unit|(?<![\w.])0 1/s")

#: Visible text outside code boxes, and visible fields without a name in words (run in the page).
_AUDIT = """
const visible = (e) => { const r = e.getBoundingClientRect(); const s = getComputedStyle(e);
  return r.width > 0 && r.height > 0 && s.visibility !== 'hidden' && s.display !== 'none'; };
const walker = document.createTreeWalker(document.body, NodeFilter.SHOW_TEXT);
const texts = [];
for (let n = walker.nextNode(); n; n = walker.nextNode()) {
  const p = n.parentElement;
  if (!p || p.closest('code, pre, script, style') || !visible(p)) continue;
  if (n.textContent.trim()) texts.push(n.textContent.trim());
}
const nameOf = (e) => {
  if (e.getAttribute('aria-label')) return e.getAttribute('aria-label');
  const by = e.getAttribute('aria-labelledby');
  if (by) return by.split(' ').map((i) => (document.getElementById(i) || {}).textContent || '').join(' ');
  const labels = [...(e.labels || [])].map((l) => l.textContent).join(' ');
  return labels;
};
const unnamed = [...document.querySelectorAll('input, select, textarea')].filter((e) => e.type !== 'hidden')
  .filter((e) => visible(e) || (e.type === 'file' && e.labels && [...e.labels].some(visible)))
  .map((e) => [e.outerHTML.slice(0, 120), nameOf(e).trim()]).filter(([, name]) => !/[A-Za-z]{3,}/.test(name));
return [texts, unnamed, document.documentElement.scrollWidth, window.innerWidth];
"""


#: The words an element shows, as WebDriver's ``.text`` gives them (see ``Page.text``).
_WORDS = r"""(e) => e.innerText.replace(/ *\t[\t ]*/g, ' ').replace(/\u00a0/g, ' ').split('\n').map((s) => s.trim())
  .filter(Boolean).join('\n')"""


#: Keeps the words of every status line shown (``window.__statusShown``), at each change of the page.
_WATCH = """
window.__statusShown = [];
const keep = () => {
  for (const e of document.querySelectorAll('[role=status]')) {
    const words = e.textContent.trim();
    if (words && e.getClientRects().length && !window.__statusShown.includes(words)) window.__statusShown.push(words);
  }
};
new MutationObserver(keep).observe(document.body, { subtree: true, childList: true, characterData: true });
"""


@functools.cache
def _visible_script() -> str:
    """A script giving the elements an XPath finds that WebDriver's own ``is_displayed`` script calls shown."""
    import pkgutil

    atom = pkgutil.get_data("selenium.webdriver.remote", "isDisplayed.js")  # the script is_displayed() sends
    assert atom, "selenium without its isDisplayed.js"
    return f"""
const shown = ({atom.decode("utf8")});
const found = document.evaluate(arguments[0], document, null, XPathResult.ORDERED_NODE_SNAPSHOT_TYPE, null);
const out = [];
for (let k = 0; k < found.snapshotLength; k++) if (shown(found.snapshotItem(k))) out.push(found.snapshotItem(k));
return out;
"""


class Page:
    """A browser tab on the app, driven by visible words."""

    def __init__(self, driver: Any, url: str, shots: Path) -> None:
        self.d, self.url, self.shots = driver, url, shots

    # -- looking -------------------------------------------------------------------------------------
    def wait(self, condition: Any, what: str, seconds: float = 240) -> Any:
        """``condition()``'s first true answer, asked every 0.1 s for two seconds, then every 0.25 s (a fit or a
        session takes seconds: the page is asked less often while it works)."""
        start = time.monotonic()
        deadline = start + seconds
        while True:
            try:
                got = condition()
            except Exception:
                got = None
            if got:
                return got
            if time.monotonic() > deadline:
                said = self.d.execute_script(
                    "return [...document.querySelectorAll('.error, [role=status], [role=alert]')]"
                    ".map(e => e.textContent).filter(Boolean)")
                pytest.fail(f"timed out waiting for {what}; the page says {said}")
            time.sleep(0.1 if time.monotonic() - start < 2 else 0.25)

    def text(self, element: Any = None) -> str:
        """The words shown in ``main`` (or in ``element``) as WebDriver's ``.text`` gives them, from the browser's
        own ``innerText`` (what is rendered: nothing hidden, no closed section; a code box's spaces as laid out): a
        table's cells parted by one space, no-break spaces as spaces, lines trimmed, blank ones dropped. WebDriver's
        ``.text`` walks the page in a script of its own, over a second on a page of plots."""
        return str(self.d.execute_script(f"return ({_WORDS})(arguments[0] || document.querySelector('main'))", element))

    def words_of(self, css: str, *, hidden: bool = False) -> str:
        """The words shown in the first element ``css`` finds (as :meth:`text`; with ``hidden``, its whole
        ``textContent``, shown or not: a code box in a closed section), found and read in one script: a page that
        draws the element again meanwhile (a result's plots arriving) leaves no stale reference."""
        read = "(e) => e.textContent" if hidden else _WORDS
        return str(self.wait(lambda: self.d.execute_script(
            f"const e = document.querySelector(arguments[0]); return e && ({read})(e)", css), f"the words of {css}"))

    def wait_text(self, words: str, seconds: float = 240) -> None:
        self.wait(lambda: words in self.text(), f"the words {words!r}", seconds)

    def watch_status(self) -> None:
        """From now on, keep the words of every status line (``role=status``) the page shows, however briefly: a
        step that a fast machine ends between two looks of ``wait`` is still seen (``shown``)."""
        self.d.execute_script(_WATCH)

    def shown(self, pattern: re.Pattern[str], what: str, seconds: float = 240) -> str:
        """The first words a status line showed since ``watch_status`` that ``pattern`` finds."""
        def seen() -> str | None:
            said = self.d.execute_script("return window.__statusShown || []")
            return next((words for words in said if pattern.search(words)), None)
        return str(self.wait(seen, what, seconds))

    def _visible(self, xpath: str) -> list[Any]:
        """The elements ``xpath`` finds that WebDriver's ``is_displayed`` calls shown (its own script, run once for
        them all rather than once an element: a round trip and 17 kB of script each)."""
        return list(self.d.execute_script(_visible_script(), xpath))

    # -- doing ---------------------------------------------------------------------------------------
    def open(self, size: tuple[int, int], *, fresh: bool = True) -> None:
        self.d.set_window_size(*size)
        self.d.get(f"{self.url}/")
        self.wait(lambda: self.d.find_element("tag name", "body").get_attribute("data-ready") == "true", "the page")
        if fresh:
            self.click("start over")
            self.wait(lambda: "kept from last time" not in self.text(), "a fresh start")

    def click(self, words: str) -> None:
        """Click the visible button, link or choice whose text holds ``words`` (the last one when several)."""
        lower = words.lower()
        upper = "ABCDEFGHIJKLMNOPQRSTUVWXYZ"
        xpath = ("//*[self::button or self::a or self::label or self::summary]"
                 f"[contains(translate(normalize-space(.), '{upper}', '{upper.lower()}'), {lower!r})]")

        def click() -> None:
            target = self.wait(lambda: self._visible(xpath), f"a control saying {words!r}")[-1]
            self.d.execute_script("arguments[0].scrollIntoView({block: 'center'})", target)
            target.click()

        self._again(click, f"the control saying {words!r}")

    def _again(self, act: Any, what: str) -> Any:
        """``act()``, done again (finding its element again) when the page re-rendered the element between
        finding it and acting on it, up to five times."""
        from selenium.common.exceptions import StaleElementReferenceException

        for _ in range(5):
            try:
                return act()
            except StaleElementReferenceException:
                time.sleep(0.2)
        pytest.fail(f"{what} was replaced five times before it could be used")

    def labelled(self, words: str) -> list[str]:
        """The ids of the controls whose visible label holds ``words``, in the page's order."""
        labels = self._visible("//label")
        named = self.d.execute_script(f"return arguments[0].map((e) => [({_WORDS})(e), e.htmlFor])", labels)
        return [control for text, control in named if words.lower() in text.lower() and control]

    def field(self, words: str) -> Any:
        """The visible input named ``words`` by its label (or aria-label)."""

        def find() -> Any:
            ids = self.labelled(words)
            return self.d.find_element("id", ids[0]) if ids else None

        return self.wait(find, f"a field labelled {words!r}")

    def type(self, words: str, value: str) -> None:
        def type_in() -> None:
            box = self.field(words)
            box.clear()
            box.send_keys(value)

        self._again(type_in, f"the field labelled {words!r}")

    def choose(self, words: str, option: str) -> None:
        from selenium.webdriver.support.ui import Select

        self._again(lambda: Select(self.field(words)).select_by_visible_text(option), f"the list labelled {words!r}")

    def upload(self, words: str, *paths: Path) -> None:
        """Choose files in the file box whose label holds ``words``."""
        names = "\n".join(str(p) for p in paths)
        self._again(lambda: self.field(words).send_keys(names), f"the file box labelled {words!r}")

    # -- checking ------------------------------------------------------------------------------------
    def check(self) -> None:
        """No flag or jargon outside code boxes, every visible field named in words, nothing scrolls sideways."""
        texts, unnamed, scroll_width, width = self.d.execute_script(_AUDIT)
        flags = [t for t in texts if _FLAG_TEXT.search(t)]
        assert not flags, f"command-line flags outside a code box: {flags[:5]}"
        jargon = [t for t in texts if JARGON.search(t)]
        assert not jargon, f"words a student does not use, outside a code box: {jargon[:5]}"
        assert not unnamed, f"fields without a name in words: {unnamed[:5]}"
        assert scroll_width <= width, f"the page is {scroll_width} px wide in a {width} px window"

    def shot(self, name: str) -> None:
        """A screenshot of the whole view, taken when ``MOTORLAB_UI_SCREENSHOTS`` names a folder (``docs/img``
        refreshes the docs' pictures; any folder to look at the pages). ``make test`` looks at none of them:
        it does not take them (each is a resize, a pause and a full-page capture)."""
        width = self.d.execute_script("return window.innerWidth")
        if not os.environ.get("MOTORLAB_UI_SCREENSHOTS"):
            assert width
            return
        height = self.d.execute_script("return document.body.scrollHeight")
        size = self.d.get_window_size()
        self.d.set_window_size(size["width"], min(max(int(height) + 120, 600), 3200))
        self.d.execute_script("window.scrollTo(0, 0)")
        time.sleep(0.3)
        self.d.save_screenshot(str(self.shots / name))
        self.d.set_window_size(size["width"], size["height"])
        assert width


def pull_from(page: Page, robot: Any) -> None:
    """Open the robot task on a fresh page and bring the files of the emulated ``robot`` (on 127.0.0.1)."""
    page.open(LAPTOP)
    page.click("Connect to the robot")
    page.type("Robot address", "127.0.0.1")
    page.type("Web server port", str(robot.http_port))
    page.type("FTC Dashboard port", str(robot.dashboard_port))
    page.click("Connect to the robot")


def make_driver() -> Any:
    """A browser on a new profile: chromedriver's own (a folder it makes and removes; the headless shell opens no
    page in a profile named with ``--user-data-dir``, and chromedriver then finds none to drive)."""
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = str(CHROMIUM)
    for flag in FLAGS:
        options.add_argument(flag)
    driver = webdriver.Chrome(service=Service(executable_path=str(CHROMEDRIVER)), options=options)
    driver.set_page_load_timeout(60)
    return driver


def foreground(page: Page) -> None:
    """Before timing the page: its browser given the CPU first, as a student's browser is the foreground program of
    their laptop, not one process among the suite's workers, simulations and app commands."""
    _foreground(page.d.service.process.pid)


#: Nice value of the browser's processes while the page is timed (:func:`foreground`).
BROWSER_NICENESS = -5


def process_tree(root: int) -> list[int]:
    """``root`` and every process under it, from Linux's /proc (``[root]`` alone elsewhere)."""
    parents: dict[int, list[int]] = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            ppid = int(stat.read_text().rsplit(")", 1)[1].split()[1])
        except (OSError, IndexError, ValueError):
            continue
        parents.setdefault(ppid, []).append(int(stat.parent.name))
    tree, k = [root], 0
    while k < len(tree):
        tree += parents.get(tree[k], [])
        k += 1
    return tree


def _foreground(root: int) -> None:
    """Give chromedriver's Chromium (every process under ``root``, the page's renderer among them)
    :data:`BROWSER_NICENESS` where this process may (root on Linux); else leave it."""
    if not Path("/proc/self/stat").is_file():
        return
    for pid in process_tree(root):
        try:
            os.setpriority(os.PRIO_PROCESS, pid, BROWSER_NICENESS)
        except (PermissionError, ProcessLookupError):
            return


class Chromium:
    """One headless Chromium lent to one test module after another, each starting as on a new profile: a single
    tab without the scripts a test added to every page, nothing the app's page stored (its IndexedDB), the window's
    first size, no permission granted. A browser that died is started again."""

    def __init__(self) -> None:
        self.origin = ""
        self.driver: Any = None
        self.size = {"width": 0, "height": 0}

    def lend(self, origin: str) -> Any:
        try:
            assert self.driver is not None
            self.driver.window_handles  # noqa: B018 (alive?)
        except Exception:
            self.quit()
            self.driver = make_driver()
            self.size = self.driver.get_window_size()
        self.origin = origin
        return self.driver

    def give_back(self) -> None:
        """The state a module leaves: closed (its tabs, their scripts and alerts), cleared (the page's stored
        state, the permissions granted), the window at its first size, on a blank page (no page of the app left
        running)."""
        d = self.driver
        if d is None:
            return
        try:
            old = d.window_handles
            d.switch_to.new_window("tab")
            kept = d.current_window_handle
            for handle in old:
                d.switch_to.window(handle)
                with contextlib.suppress(Exception):  # an alert left open
                    d.switch_to.alert.dismiss()
                d.close()
            d.switch_to.window(kept)
            d.execute_cdp_cmd("Storage.clearDataForOrigin", {"origin": self.origin, "storageTypes": "all"})
            d.execute_cdp_cmd("Browser.resetPermissions", {})  # the clipboard a test granted
            d.set_window_size(self.size["width"], self.size["height"])
        except Exception:  # a browser left in a state it cannot leave: the next module gets a new one
            self.quit()

    def quit(self) -> None:
        if self.driver is not None:
            with contextlib.suppress(Exception):
                self.driver.quit()
        self.driver = None


def shots_folder(tmp: Path) -> Path:
    folder = Path(os.environ.get("MOTORLAB_UI_SCREENSHOTS") or tmp)
    folder.mkdir(parents=True, exist_ok=True)
    return folder


def kv_per_tick(page: Page) -> float:
    """kV per encoder tick as the Road Runner code to paste says it (``kV = 9.6e-05;  // V*s/tick``)."""
    code = page.wait(lambda: [e.text for e in page.d.find_elements("css selector", "pre code") if "kV =" in e.text],
                     "the code to paste")[0]
    found = re.search(r"kV = ([0-9.eE+-]+);\s*// V\*s/tick", code)
    assert found, code
    return float(found.group(1))


#: Long tasks of the page's main thread (Chromium's long-task timing, ``PerformanceObserver('longtask')``), kept in
#: ``window.__long`` as [start, duration] from the page's start: install with ``Page.addScriptToEvaluateOnNewDocument``.
LONG_TASKS = """
window.__long = [];
try {
  const seen = (list) => { for (const e of list.getEntries()) window.__long.push([e.startTime, e.duration]); };
  new PerformanceObserver(seen).observe({ type: "longtask", buffered: true });
} catch (e) { window.__long = null; }
"""
#: Load average per CPU above which the long-task timing measures the machine, not the page: Chromium's tasks
#: then wait for a CPU (a figure drawn in 60-100 ms on a quiet machine took 1.6-2.1 s at a load of 17 on 2 CPUs).
BUSY = 1.5
#: Share of the watched time in which some runnable thread waited for a CPU (Linux's pressure stall
#: information, ``/proc/pressure/cpu``) above which the same holds: 0.18-0.20 while a SysId file is fitted and
#: drawn on a quiet 2-CPU machine (the fit's process, the browser's and the test's share it), 0.58 with two more
#: programs busy (tasks of the page then 53-90 ms, the browser given the CPU first).
WAITING = 0.35


def load_per_cpu() -> float:
    return os.getloadavg()[0] / (os.cpu_count() or 1)


def _cpu_waited() -> float | None:
    """Seconds during which some runnable thread of this machine has waited for a CPU since it started."""
    try:
        some = Path("/proc/pressure/cpu").read_text().splitlines()[0]
    except (OSError, IndexError):
        return None
    return int(some.rsplit("total=", 1)[1]) / 1e6


class Contention:
    """How busy the machine is while a page is timed, from now to :meth:`end`: the load average per CPU at the
    start and at the end, and the share of the time between in which a thread waited for a CPU (what a long task
    of the page then holds besides the page's own work)."""

    def __init__(self) -> None:
        self.load, self.start, self.waited = load_per_cpu(), time.monotonic(), _cpu_waited()
        self.why: str | None = None

    def end(self) -> None:
        """The timed stretch is over: say whether its timing measured the machine (:attr:`why`) or the page."""
        load = max(self.load, load_per_cpu())
        now = _cpu_waited()
        share = None if now is None or self.waited is None else (now - self.waited) / max(
            time.monotonic() - self.start, 1e-3)
        if load > BUSY:
            self.why = f"load average {load:.1f} per CPU"
        elif share is not None and share > WAITING:
            self.why = f"threads waited for a CPU {share:.0%} of the time"


def no_long_task_after(long_tasks: list[list[float]] | None, since: float, machine: Contention) -> None:
    """No task of 200 ms or more after ``since`` (the page's clock); on a machine busier than :data:`BUSY` or
    :data:`WAITING` while it was timed (``machine``, ended), the timing is the machine's, and the test says so by
    skipping (everything before it has passed)."""
    if long_tasks is None:  # a browser without the long-task timing
        return
    late = [round(d) for start, d in long_tasks if start >= since]
    if late and max(late) >= 200 and machine.why:
        pytest.skip(f"the machine is busy ({machine.why}): tasks after the result {late} ms measure its load, "
                    "not the page")
    assert not late or max(late) < 200, f"tasks of 200 ms or more while results are shown: {late}"
