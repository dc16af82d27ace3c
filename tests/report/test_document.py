"""The HTML report: self-contained, parseable, every figure a PNG data URI, every unit present; Chromium renders it."""

from __future__ import annotations

import base64
import shutil
import subprocess
from html.parser import HTMLParser
from pathlib import Path

import pytest

from motorlab.report.document import image_sources, render_report, write_report
from motorlab.session.characterize import characterize
from motorlab.session.simulated import write_simulated_session
from motorlab.session.spec import load_session
from motorlab.units import format_value

ROOT = Path(__file__).resolve().parents[2]
CHROMIUM = (shutil.which("chromium-headless-shell") or shutil.which("chromium")
            or ("/usr/bin/chromium" if Path("/usr/bin/chromium").exists() else None))


@pytest.fixture(scope="module")
def result(tmp_path_factory: pytest.TempPathFactory):  # type: ignore[no-untyped-def]
    out = tmp_path_factory.mktemp("session")
    toml = write_simulated_session("neverest20", out_dir=out, units=3, seed=2, experiments=("lcr", "spindown"))
    # A label with markup must come out escaped.
    text = toml.read_text().replace("[units.A]\n", '[units.A]\nlabel = "AM 20 <A> & co"\n', 1)
    toml.write_text(text)
    return characterize(load_session(toml))


@pytest.fixture(scope="module")
def document(result) -> str:  # type: ignore[no-untyped-def]
    return render_report(result)


class _Collector(HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.tags: list[str] = []
        self.text: list[str] = []
        self.rows: list[list[str]] = []
        self._row: list[str] | None = None

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        self.tags.append(tag)
        if tag == "tr":
            self._row = []

    def handle_endtag(self, tag: str) -> None:
        if tag == "tr" and self._row is not None:
            self.rows.append(self._row)
            self._row = None

    def handle_data(self, data: str) -> None:
        self.text.append(data)
        if self._row is not None and data.strip():
            self._row.append(data.strip())


def test_report_parses_and_is_self_contained(document: str) -> None:
    parser = _Collector()
    parser.feed(document)
    parser.close()
    assert "script" not in parser.tags
    assert "link" not in parser.tags
    assert "http://" not in document.split("<body>")[0]
    assert 'src="http' not in document
    images = list(image_sources(document))
    # 3 units × 2 experiments + 3 motor-curve figures (no J measured: no gains).
    assert len(images) == 9
    for src in images:
        assert src.startswith("data:image/png;base64,")
        png = base64.b64decode(src.split(",", 1)[1], validate=True)
        assert png[:8] == b"\x89PNG\r\n\x1a\n"
        assert len(png) > 5000
    text = " ".join(parser.text)
    for label in ("AM 20 <A> & co", "B", "C"):
        assert any(row and row[0] == label for row in parser.rows), label
    assert "<A> & co" not in document
    assert "AM 20 &lt;A&gt; &amp; co" in document
    for needle in ("Final parameters", "Fleet", "Motor curves", "Methods", "omits the ½", "(K·I − Tf)/ω"):
        assert needle in text, needle
    assert "@media print" in document


def test_text_only_report_and_formatting(result, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    path = write_report(result, tmp_path / "r.html", figures=False)
    assert list(image_sources(path.read_text())) == []
    assert format_value(0.68371, 0.00095) == "0.68371 ± 0.00095"
    assert format_value(690e-6, 9.8e-6, scale=1e6) == "690.0 ± 9.8"
    assert format_value(1.5e-6, 2e-8) == "(1.500 ± 0.020) × 10⁻⁶"
    assert format_value(0.0144627, 1.5e-6) == "(1.44627 ± 0.00015) × 10⁻²"  # a flywheel's J, as the app writes it
    assert format_value(123456.0, 12.0) == "(1.23456 ± 0.00012) × 10⁵"
    assert format_value(0.0, 1e-9) == "(0.0 ± 1.0) × 10⁻⁹"
    assert format_value(float("nan"), 1.0) == "—"


@pytest.mark.skipif(CHROMIUM is None, reason="chromium is not installed (apt-get install chromium)")
def test_report_renders_in_headless_chromium(document: str, tmp_path: Path) -> None:
    html = tmp_path / "report.html"
    html.write_text(document, encoding="utf-8")
    png = tmp_path / "report.png"
    run = subprocess.run(
        ["sh", str(ROOT / "scripts" / "render_report.sh"), str(html), str(png), "2500"],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
        env={"PATH": "/usr/bin:/bin", "CHROMIUM": CHROMIUM or "", "HOME": str(tmp_path)},
    )
    assert run.returncode == 0, run.stderr
    data = png.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    width = int.from_bytes(data[16:20], "big")
    height = int.from_bytes(data[20:24], "big")
    assert (width, height) == (1200, 2500)
    assert len(data) > 50_000  # a page of tables and figures, not a blank screenshot


def test_report_drawn_in_two_processes_is_the_same_document(result, document: str) -> None:  # type: ignore[no-untyped-def]
    from motorlab import progress

    seen: list[progress.Progress] = []
    with progress.reporting(seen.append):
        shared = render_report(result, processes=2)
    assert shared == document  # each section drawn once, in whichever process, put back in order
    drawing = [p for p in seen if p.what == "Drawing the report"]
    assert drawing[-1].finished
    assert drawing[-1].done == drawing[-1].total == 5  # the curves, three units, the gains


def test_the_gains_line_gives_each_parameter_its_unit() -> None:
    from types import SimpleNamespace

    from motorlab.report.document import _gains_section

    gains = {"motor": "median of the units", "voltage": 12.0, "text": "velocity loop ...",
             "params": {"K": 0.37, "R": 1.16, "L": 6.6e-4, "J": 1.2e-4, "b": 2.5e-5, "Tf": 0.011}}
    html = _gains_section(SimpleNamespace(gains=gains), figures=False)  # type: ignore[arg-type]
    for shown in ("K = 0.37 V·s/rad", "R = 1.16 Ω", "L = 660 µH", "J = 1.2 × 10⁻⁴ kg·m²", "b = 2.5 × 10⁻⁵ N·m·s/rad",
                  "Tf = 0.011 N·m"):
        assert shown in html, (shown, html)
