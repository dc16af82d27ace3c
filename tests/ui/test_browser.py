"""The app in a real browser: Debian's Chromium driven by Selenium, headless.

Upload a simulated spin-down log, pick the motor, run, read the table against the simulated truth,
compute gains and use a copy button, and check that the page loaded nothing from another host.
Skips (saying why) only when chromium or chromedriver is not installed (``.ci/run`` installs both).
Set ``MOTORLAB_UI_SCREENSHOTS=DIR`` to keep the screenshots (docs/ui.md shows them).
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path
from typing import Any

import pytest

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
CHROMEDRIVER = shutil.which("chromedriver")

pytestmark = pytest.mark.skipif(
    CHROMIUM is None or CHROMEDRIVER is None,
    reason="needs Debian's chromium and chromium-driver (apt-get install chromium chromium-driver; .ci/run does)",
)

FLAGS = (
    "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
    "--window-size=1280,1800",
)


@pytest.fixture
def browser(tmp_path: Path) -> Any:
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = str(CHROMIUM)
    for flag in (*FLAGS, f"--user-data-dir={tmp_path / 'profile'}"):
        options.add_argument(flag)
    driver = webdriver.Chrome(service=Service(executable_path=str(CHROMEDRIVER)), options=options)
    driver.set_page_load_timeout(60)
    yield driver
    driver.quit()


class _Wait:
    """``WebDriverWait.until`` whose timeout names what was awaited and the page's own error lines."""

    def __init__(self, driver: Any, seconds: float) -> None:
        from selenium.webdriver.support.ui import WebDriverWait

        self.driver, self.inner = driver, WebDriverWait(driver, seconds)

    def until(self, condition: Any, what: str = "") -> Any:
        from selenium.common.exceptions import TimeoutException

        try:
            return self.inner.until(condition)
        except TimeoutException:
            errors = self.driver.execute_script(
                "return [...document.querySelectorAll('.error, [role=status]')].map(e => e.id + ': ' + e.textContent)"
            )
            pytest.fail(f"timed out waiting for {what}; the page says {errors}")


def _screenshot(driver: Any, tmp_path: Path, name: str) -> Path:
    folder = Path(os.environ.get("MOTORLAB_UI_SCREENSHOTS") or tmp_path)
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / name
    height = driver.execute_script("return document.body.scrollHeight")
    driver.set_window_size(1280, min(max(int(height) + 40, 900), 4000))
    driver.save_screenshot(str(path))
    return path


def test_upload_run_read_copy(browser: Any, server: Any, sim_session: Path, truth: dict[str, Any],
                              tmp_path: Path) -> None:
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support import expected_conditions as ec
    from selenium.webdriver.support.ui import Select

    wait = _Wait(browser, 90)
    browser.get(f"{server.url}/")
    wait.until(lambda d: d.find_element(By.TAG_NAME, "body").get_attribute("data-ready") == "true")
    file_input = browser.find_element(By.ID, "files")
    assert file_input.is_displayed()
    file_input.send_keys(str(sim_session / "A" / "spindown.txt"))
    wait.until(ec.text_to_be_present_in_element((By.ID, "detected"), "ftc-log"))
    assert Select(browser.find_element(By.ID, "experiment")).first_selected_option.text == "spindown"
    wait.until(lambda d: d.find_elements(By.CSS_SELECTOR, "#raw-plot .main-svg"))  # the raw data, plotted at once
    Select(browser.find_element(By.ID, "motor")).select_by_value("neverest40")  # fills the counts per revolution
    assert browser.find_element(By.ID, "opt-cpr").get_attribute("value") == "1120"
    browser.find_element(By.ID, "run").click()
    row = wait.until(ec.visibility_of_element_located((By.CSS_SELECTOR, "#results tr[data-name='K']")), "the table")
    value = float(row.find_element(By.CLASS_NAME, "value").text)
    stderr = float(row.find_element(By.CLASS_NAME, "stderr").text)
    true_k = truth["runs"]["spindown.txt"]["params"]["K"]
    assert abs(value - true_k) < 4 * stderr
    assert abs(value - true_k) / true_k < 0.02
    wait.until(lambda d: d.find_elements(By.CSS_SELECTOR, "#fit-plot .main-svg"))  # data against fit, residuals
    _screenshot(browser, tmp_path, "ui-analyze.png")

    browser.find_element(By.ID, "to-gains").click()
    browser.find_element(By.ID, "tune-kv").send_keys("1.2")
    browser.find_element(By.ID, "tune-ka").send_keys("0.1")
    Select(browser.find_element(By.ID, "tune-target")).select_by_value("ftc-pidf")
    browser.find_element(By.ID, "run-tune").click()
    copy = wait.until(ec.element_to_be_clickable((By.CSS_SELECTOR, ".copy[data-lang='java']")), "the snippets")
    browser.execute_cdp_cmd("Browser.grantPermissions", {
        "origin": server.url, "permissions": ["clipboardReadWrite", "clipboardSanitizedWrite"]})
    copy.click()
    wait.until(lambda d: copy.text == "Copied", "the copy button's answer")
    snippet = browser.find_element(By.CSS_SELECTOR, ".snippet pre").text
    pasted = browser.execute_async_script(
        "navigator.clipboard.readText().then(arguments[0], e => arguments[0](String(e)))"
    )
    assert pasted.strip() == snippet.strip()
    assert "setVelocityPIDFCoefficients" in pasted
    figure = browser.find_element(By.ID, "step-figure")
    wait.until(lambda d: figure.get_attribute("naturalWidth") not in (None, "0"), "the step figure")
    _screenshot(browser, tmp_path, "ui-gains.png")

    archive = Path(shutil.make_archive(str(tmp_path / "bench"), "zip", sim_session))  # a whole session, zipped
    browser.find_element(By.ID, "tab-session").click()
    browser.find_element(By.ID, "session-files").send_keys(str(archive))
    browser.find_element(By.ID, "run-session").click()
    wait.until(ec.visibility_of_element_located((By.CSS_SELECTOR, "#session-table tbody tr")), "the session table")
    assert browser.find_element(By.CSS_SELECTOR, "#session-table tbody td:nth-child(2)").text == "ok"
    assert browser.find_elements(By.CSS_SELECTOR, "#fleet-table tbody tr")
    _screenshot(browser, tmp_path, "ui-session.png")

    loaded = browser.execute_script(
        "return [location.href, ...performance.getEntriesByType('resource').map(e => e.name)]"
    )
    foreign = [url for url in loaded if not url.startswith((server.url, "blob:", "data:"))]
    assert not foreign, foreign
    assert any(url.endswith("/static/plotly.min.js") for url in loaded)
