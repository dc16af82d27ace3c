"""Regenerate the option tables of docs/analyze.md from the experiments' descriptions.

    python scripts/experiment_docs.py          # rewrite the tables
    python scripts/experiment_docs.py --check  # exit 1 if they are out of date

tests/experiments/test_registry.py runs the check.
"""

from __future__ import annotations

import sys
from pathlib import Path

from motorlab.experiments import DOCS_BEGIN, DOCS_END, options_markdown

DOC = Path(__file__).resolve().parents[1] / "docs" / "analyze.md"


def render(text: str) -> str:
    """``text`` with the part between the markers replaced by the current tables."""
    head, rest = text.split(DOCS_BEGIN, 1)
    _old, tail = rest.split(DOCS_END, 1)
    return f"{head}{DOCS_BEGIN}\n\n{options_markdown()}\n{DOCS_END}{tail}"


def main() -> int:
    text = DOC.read_text(encoding="utf-8")
    new = render(text)
    if "--check" in sys.argv[1:]:
        if new != text:
            print(f"{DOC}: the option tables are out of date; run python scripts/experiment_docs.py", file=sys.stderr)
            return 1
        return 0
    DOC.write_text(new, encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
