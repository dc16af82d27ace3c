"""Every file of the page ships in the wheel: pyproject's package-data covers the static folder's subfolders."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
STATIC = ROOT / "src" / "motorlab" / "ui" / "static"


def test_package_data_covers_every_static_file() -> None:
    patterns = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["package-data"]["motorlab"]
    package = ROOT / "src" / "motorlab"
    shipped = {p for pattern in patterns for p in package.glob(pattern) if p.is_file()}
    assets = {p for p in STATIC.rglob("*") if p.is_file()}
    assert assets, "no static files found"
    assert assets <= shipped, sorted(str(p.relative_to(STATIC)) for p in assets - shipped)


def test_page_modules_import_only_shipped_files() -> None:
    """Every ES module the page imports exists (no build step: a typo is a blank page)."""
    for module in STATIC.rglob("*.js"):
        for target in re.findall(r'^import .* from "(\.[^"]+)";', module.read_text(), flags=re.M):
            assert (module.parent / target).resolve().is_file(), f"{module.name} imports {target}"
