"""Run the notebook walk-through of docs/notebook.md on a simulated session and draw its figures.

    MPLBACKEND=Agg python scripts/notebook_walkthrough.py [OUT_DIR]

Simulates one NeveRest 40 on the virtual dynamometer (seed 0), fits every experiment with the
notebook API and prints the results; figures go to docs/img/notebook-*.png.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import motorlab as ml
from motorlab.plot import save_figure
from motorlab.session.simulated import write_simulated_session

#: The session's flywheel (0.019527634 kg·m², ratio 25) at the encoder shaft: J·N² [kg·m²].
INERTIA = 0.019527634 * 25**2
FIGURES = Path(__file__).resolve().parents[1] / "docs" / "img"


def main() -> None:
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tempfile.mkdtemp())
    write_simulated_session("neverest40", out_dir=out, units=1, seed=0)
    a = out / "A"
    lcr = ml.lcr(a / "lcr.csv")
    torque = ml.torque(a / "torque.csv")
    k = torque["K"]
    fits = {
        "lcr": lcr,
        "torque": torque,
        "spindown": ml.spindown(a / "spindown.txt", cpr=1120, inertia=INERTIA),
        "terminal": ml.terminal(a / "terminal.csv", K=k.value, K_stderr=k.stderr),
        "free-spinup": ml.free_spinup(a / "free_spinup.csv", K=k.value, current="0.5 A"),
        "spinup": ml.spinup(a / "spinup.txt", cpr=1120, inertia=INERTIA, spindown=[a / "spindown.txt"]),
        "amplifier": ml.amplifier(a / "amplifier.csv", nominal="2 A/V"),
        "tachometer": ml.tachometer(a / "tachometer.csv"),
        "pulse": ml.pulse(a / "pulse.csv", Km=k.value),
        "identify": ml.identify(a / "transient.csv"),
        "feedforward": ml.feedforward(a / "sysid.json"),
    }
    for name, fit in fits.items():
        print(f">>> {name}")
        print(repr(fit))
    FIGURES.mkdir(exist_ok=True)
    save_figure(fits["spindown"].plot(), FIGURES / "notebook-spindown.png")


if __name__ == "__main__":
    main()
