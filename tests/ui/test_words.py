"""The page reads every word from /api/schema (issue 33, point 4): labels, help, choices in words, experiment
titles, parameter and gain names, targets and tasks come from the experiment descriptions and
motorlab.glossary; no JavaScript file of the app keeps a copy of any of them (a copy drifts: "Spin-down:
coasting…" against the description's "Flywheel spin-down")."""

from __future__ import annotations

import re
from collections.abc import Iterator
from importlib import resources
from pathlib import Path
from typing import Any

import httpx

from motorlab.ui.schema import schema

JS = Path(str(resources.files("motorlab.ui") / "static" / "js"))

#: A JavaScript string literal: "…", '…' or `…` (escapes kept).
_LITERAL = re.compile(r'"((?:[^"\\\n]|\\.)*)"|\'((?:[^\'\\\n]|\\.)*)\'|`((?:[^`\\]|\\.)*)`')


def _words(s: dict[str, Any]) -> Iterator[str]:
    """Every word-bearing string of the schema: what the page shows for the names motorlab uses."""
    fields = [f for exp in s["analyze"].values() for f in exp["fields"]]
    fields += [f for command in ("characterize", "tune") for f in s[command]["fields"]]
    for f in fields:
        yield f["label"]
        yield f["help"]
        yield from f["choice_labels"] or []
    for exp in s["analyze"].values():
        yield exp["title"]
        yield exp["description"]
    yield from (p["name"] for p in s["parameters"].values())
    yield from (t["label"] for t in s["targets"])
    for task in s["tasks"].values():
        yield from task.values()
    yield from s["gains"].values()
    yield from s["measured_by"].values()


def _literals(text: str) -> Iterator[str]:
    for found in _LITERAL.finditer(text):
        yield next(g for g in found.groups() if g is not None)


def test_no_script_keeps_a_word_the_schema_has() -> None:
    words = {w.strip() for w in _words(schema()) if w and " " in w.strip()}  # names in words, not one word
    long = {w for w in words if len(w) >= 16}
    copies = []
    for path in sorted(JS.rglob("*.js")):
        text = path.read_text(encoding="utf-8")
        copies += [(path.name, lit) for lit in _literals(text) if lit.strip() in words]
        copies += [(path.name, w) for w in long if w in text]
    assert not copies, f"words the schema has, copied into the scripts: {sorted(set(copies))[:12]}"


def test_the_schema_holds_the_words_the_page_needs() -> None:
    s = schema()
    assert set(s["tasks"]) >= {"drive", "mechanism", "bench", "expert"}
    assert all(t["title"] and t["short"] and t["needs"] for t in s["tasks"].values())
    side = next(f for f in s["analyze"]["feedforward"]["fields"] if f["name"] == "side")
    assert side["choice_labels"] == ["both sides", "left side", "right side"]
    friction = next(f for f in s["analyze"]["pulse"]["fields"] if f["name"] == "friction")
    assert "both sides" not in friction["choice_labels"]  # the same choice of another option: its own words
    target = next(f for f in s["tune"]["fields"] if f["name"] == "target")
    assert target["choice_labels"][target["choices"].index("wpilib")] == next(
        t["label"] for t in s["targets"] if t["key"] == "wpilib")


def test_the_schemas_words_are_a_students() -> None:
    """Every label, help, choice, title and name the page shows from the schema, held to the jargon list."""
    import ui_browser as browser

    jargon = sorted({w for w in _words(schema()) if w and browser.JARGON.search(w)})
    assert not jargon, jargon[:8]


def test_the_page_shows_the_schemas_titles(page: Any, server: Any, tmp_path: Path) -> None:
    import ui_browser as browser  # tests/ui/browser.py, loaded by conftest.py

    s = httpx.get(f"{server.url}/api/schema", timeout=30).json()
    page.open(browser.LAPTOP)
    text = page.text()
    for task in ("drive", "mechanism", "bench", "expert"):
        assert s["tasks"][task]["title"] in text
    page.click(s["tasks"]["expert"]["title"])
    path = tmp_path / "lcr.csv"
    path.write_text("frequency_Hz,L_uH,Q,DCR_ohm\n1000,690,3.1,2.1\n1000,692,3.0,2.1\n", encoding="utf-8")
    page.upload("Choose or drop your files", path)
    page.wait_text(f"Proposed: {s['analyze']['lcr']['title']}")
    menu = page.field("What this file measures")
    shown = [o.text for o in menu.find_elements("tag name", "option")]
    assert shown == [exp["title"] for exp in s["analyze"].values()]
    assert page.d.title == f"motorlab · {s['tasks']['expert']['short']}"
    page.check()


def test_numbers_are_rounded_to_their_uncertainty_with_a_unit(page: Any) -> None:
    """format.js, run in the page: two significant digits of the standard error, no false precision, units."""
    import ui_browser as browser

    page.open(browser.PHONE, fresh=False)
    shown = page.d.execute_async_script("""
      const done = arguments[arguments.length - 1];
      import('/static/js/format.js').then((f) => done([
        f.quantity(0.018967894, 1.3e-9, 'm'), f.quantity(0.125318, 0.0000153, 'V*s/rad'),
        f.quantity(9.6123e-5, 1.2e-7, 'V*s/tick'), f.quantity(0.00069, 0.00001, 'H'),
        f.overshoot(4.11e-4), f.overshoot(9.489), f.overshoot(null),
        f.quantity(0, null, '1/s'), f.prettyUnit('hub/(tick/s)'), f.prettyUnit('hub'),
        f.settledError(-4.568e-6, 54.0, 'rot/s'), f.settledError(-0.6, 54.0, 'rot/s'),
        f.settledError(null, 54.0, 'rad'), f.quantity(0.675, 1e-6, 'V*s/rad'),
        f.quantity(0.0127900, 1e-7, 'kg*m^2'), f.share(0.9999996), f.share(0.98764), f.share(null),
        f.correlation(-0.99961), f.correlation(0.5)]));""")
    assert shown == [
        "18.968 mm (uncertainty below 0.01 %)",  # not (1.8967894 ± 0.0000013) × 10⁻²
        "0.125318 ± 0.000015 V·s/rad",
        "(9.612 ± 0.012) × 10⁻⁵ V·s/tick",
        "690 ± 10 µH",
        "no overshoot", "9.5 %", "no overshoot",  # not "4.11 × 10⁻⁴ %"
        "0 s⁻¹",  # not "0 1/s"
        "output/(tick/s)", "output",  # the controller's output, not "hub" as a unit
        "none (below 0.1 % of the step)", "-0.6 rot/s", "not determined",  # not "-4.568 × 10⁻⁶ rot/s"
        "0.67500 V·s/rad (uncertainty below 0.01 %)",  # five digits known, not "0.675"
        "0.012790 kg·m² (uncertainty below 0.01 %)",
        "above 0.9999", "0.9876", "not determined",  # R², not "1"
        "−1.00", "0.50",  # a correlation, not "-1"
    ]
