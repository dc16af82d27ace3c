"""Where the tests and benchmarks find the public real data: read in place, never copied into the project.

Logs that others recorded and published (teams' SysId and frc-characterization JSON, VEX Robotics' dynamometer
exports, an FTC team's Datalogger files, Road Runner's encoder test data) live in ``../shared/data/real`` beside
the clone (CI has it there; from a worktree ``wt/NAME`` the folder two levels up), or wherever
``MOTORLAB_REAL_DATA`` names. Each subfolder has a README with the files' provenance. The project keeps in
``tests/data`` only the small files it made itself.

No pytest here: ``scripts/fuzz.py`` and the benchmarks use it too; ``tests/conftest.py`` turns it into the
``real_dir`` and ``dyno_dir`` fixtures, which skip a test, saying where they looked, when the folder is absent.
"""

from __future__ import annotations

import os
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def candidates() -> list[Path]:
    """The places looked at, in order: ``$MOTORLAB_REAL_DATA``, then ``../shared/data/real`` beside the clone or
    two levels up (a git worktree under ``wt/``)."""
    env = os.environ.get("MOTORLAB_REAL_DATA")
    beside = [base / "shared" / "data" / "real" for base in (ROOT.parent, ROOT.parent.parent)]
    return ([Path(env)] if env else []) + beside


def find_real_dir() -> Path | None:
    """The shared folder of real data (it holds a README.md), or None when this checkout has none beside it."""
    return next((p for p in candidates() if (p / "README.md").is_file()), None)


def find_dyno_dir() -> Path | None:
    """VEX Robotics' dynamometer exports in the shared folder (``dyno/``), or None."""
    real = find_real_dir()
    return real / "dyno" if real is not None and (real / "dyno" / "README.md").is_file() else None


def not_found(what: str) -> str:
    """The one line a test or benchmark gives when the shared real data are absent: what, and where it looked."""
    places = ", ".join(str(p) for p in candidates())
    return f"{what} are not beside this clone (looked in {places}; set MOTORLAB_REAL_DATA to the folder)"


def team_gains(sysid: Path) -> dict[str, tuple[float, float, float]]:
    """The gains the teams published for the scored SysId logs: ``file -> (kS [V], kV [V/(u/s)], kA [V/(u/s²)])``
    in each file's own units, read from the table of ``sysid/README.md`` (columns file, mechanism, units, kS, kV,
    kA, source; a minus sign may be U+2212)."""
    out = {}
    for line in (sysid / "README.md").read_text(encoding="utf-8").splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 7 and cells[0].startswith("`") and cells[0].endswith(".json`"):
            ks, kv, ka = (float(c.replace("\u2212", "-")) for c in cells[3:6])
            out[cells[0].strip("`")] = (ks, kv, ka)
    if not out:
        raise ValueError(f"{sysid / 'README.md'}: no table of the teams' gains (| `file.json` | … | kS | kV | kA | …)")
    return out
