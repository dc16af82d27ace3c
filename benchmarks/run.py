"""Run every ``bench_*.py`` in this folder as a script and print what each reports.

Timings live here, never in pass/fail tests: ``make bench``.
"""

from __future__ import annotations

import runpy
import sys
from pathlib import Path


def main() -> int:
    here = Path(__file__).resolve().parent
    names = sys.argv[1:]
    scripts = sorted(here.glob("bench_*.py"))
    if names:
        scripts = [s for s in scripts if any(n in s.stem for n in names)]
    for script in scripts:
        print(f"== {script.name}")
        runpy.run_path(str(script), run_name="__main__")
        print()
    return 0


if __name__ == "__main__":
    sys.exit(main())
