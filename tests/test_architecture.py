"""The layering of issue 15, measured on the source (scripts/measure_architecture.py)."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

import pytest

SCRIPT = Path(__file__).resolve().parents[1] / "scripts" / "measure_architecture.py"


@pytest.fixture(scope="module")
def measures() -> tuple:
    spec = importlib.util.spec_from_file_location("measure_architecture", SCRIPT)
    assert spec is not None
    assert spec.loader is not None
    module: ModuleType = importlib.util.module_from_spec(spec)
    sys.modules["measure_architecture"] = module
    spec.loader.exec_module(module)
    return module.measure()


def test_no_library_module_imports_the_cli(measures: tuple) -> None:
    assert measures.cli_imports == []  # nor the browser app, the other front end


def test_no_function_over_100_lines(measures: tuple) -> None:
    assert measures.long_functions == []  # counted from ``def`` to the last line, docstring included


def test_python_control_is_for_tests_only(measures: tuple) -> None:
    assert measures.control_imports == []


def test_no_import_circles(measures: tuple) -> None:
    assert measures.cycles == []


def test_no_module_over_800_lines(measures: tuple) -> None:
    assert measures.long_modules == []


def test_at_most_twenty_modules_at_the_root(measures: tuple) -> None:
    assert len(measures.root_modules) <= 20, measures.root_modules  # the rest live in the package of their job


def test_few_imports_of_another_modules_private_names(measures: tuple) -> None:
    assert len(measures.private_imports) <= 5, measures.private_imports


def test_one_newey_west_rule_and_one_not_determined_rule() -> None:
    """Every fit's standard errors follow estimation/covariance.py: no other module computes a long-run
    covariance (a Bartlett-weighted sum of lagged scores) or keeps its own tolerance on singular values."""
    import ast

    src = Path(__file__).resolve().parents[1] / "src" / "motorlab"
    bartlett, tolerances = [], []
    for path in src.rglob("*.py"):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.FunctionDef) and ("bartlett" in node.name or node.name == "hac_meat"):
                bartlett.append(f"{path.relative_to(src)}:{node.name}")
            if isinstance(node, ast.Assign):
                names = [t.id for t in node.targets if isinstance(t, ast.Name)]
                if any(n.endswith("TOLERANCE") and ("NULL" in n or "SINGULAR" in n or "INFO" in n) for n in names):
                    tolerances.append(f"{path.relative_to(src)}:{names}")
    assert bartlett, "no Newey–West rule found"
    assert all(b.startswith("estimation/covariance.py") for b in bartlett), bartlett
    assert tolerances == ["estimation/covariance.py:['NULL_TOLERANCE']"], tolerances
