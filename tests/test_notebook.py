"""The notebook API: ml.<experiment>(files, **options) gives what `motorlab analyze` gives."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from matplotlib.figure import Figure

import motorlab as ml
from motorlab.cli import main
from motorlab.errors import OptionError
from motorlab.session.simulated import write_simulated_session

FLYWHEEL = 0.019527634 * 25**2  # kg·m², the simulated session's flywheel J·N² at the encoder shaft


@pytest.fixture(scope="module")
def unit(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("nb")
    write_simulated_session("neverest40", out_dir=out, units=1, seed=3, experiments=["spindown", "lcr"])
    return out / "A"


def test_spindown_matches_the_cli_and_the_truth(unit: Path, capsys: pytest.CaptureFixture[str]) -> None:
    fit = ml.spindown(unit / "spindown.txt", cpr=1120, inertia=f"{FLYWHEEL * 1000} g*m^2")
    assert main(["analyze", "spindown", str(unit / "spindown.txt"), "--cpr", "1120",
                 "--inertia", str(FLYWHEEL), "--json"]) == 0
    cli = json.loads(capsys.readouterr().out)
    for name, est in fit.to_dict()["parameters"].items():
        assert est["value"] == pytest.approx(cli["parameters"][name]["value"], rel=1e-9)
        assert est["unit"] == cli["parameters"][name]["unit"]
    assert fit.details["shaft"] == cli["details"]["shaft"]
    truth = json.loads((unit / "truth.json").read_text())
    assert "K" in fit
    k_true = truth["runs"]["spindown.txt"]["params"]["K"]
    assert abs(fit.value("K") - k_true) < 5 * fit["K"].stderr + 0.02 * k_true


def test_repr_html_plot_rows(unit: Path) -> None:
    fit = ml.lcr(unit / "lcr.csv")
    text = repr(fit)
    assert text.startswith("FitResult('lcr'")
    assert len(text) < 1000  # not the arrays behind the plots
    assert "R = " in text
    assert "Ω" in text
    html = fit._repr_html_()
    assert "<table>" in html
    assert "± " in html
    assert "shaft: electrical" in html
    assert isinstance(fit.plot(), Figure)
    fig = Figure()
    ax = fig.add_subplot()
    assert fit.plot(ax=ax) is ax
    assert ax.get_lines()
    rows = fit.to_rows()
    assert [r["parameter"] for r in rows] == list(fit.parameters)
    assert rows[0]["unit"] == "ohm"
    assert math.isclose(rows[0]["value"], fit.value("R"))
    csv_text = fit.to_csv()
    assert csv_text.splitlines()[0].startswith("experiment,parameter,value,stderr,unit")
    assert len(csv_text.splitlines()) == len(rows) + 1


def test_options_are_checked(unit: Path) -> None:
    with pytest.raises(OptionError, match="unknown option"):
        ml.spindown(unit / "spindown.txt", cpr=1120, inertial=1.0)
    with pytest.raises(OptionError, match="cpr"):
        ml.spindown(unit / "spindown.txt", cpr="-3")
    with pytest.raises(OptionError, match="give Km"):
        ml.pulse(unit / "lcr.csv")
    with pytest.raises(OptionError, match="unknown experiment"):
        ml.analyze("nosuch", unit / "lcr.csv")
    names = {o["keyword"] for o in ml.describe("spindown")}
    assert {"cpr", "inertia", "inertia_stderr", "cutoff", "guard"} <= names


def test_identify_and_feedforward_stay_callable_after_their_modules_load() -> None:
    import motorlab.analyses.feedforward
    import motorlab.analyses.identify

    assert callable(ml.identify)
    assert callable(ml.feedforward)
    assert callable(motorlab.analyses.identify.identify)  # the library function is untouched


def test_read_gives_a_short_repr(unit: Path) -> None:
    rec = ml.read(unit / "spindown.txt", cpr="1120 count")
    assert "position" in rec.signals
    assert repr(rec).startswith("Recording(")
    assert len(repr(rec)) < 300


def test_no_name_is_both_a_module_and_a_function() -> None:
    """``from motorlab import identify`` is the experiment's function (its module is motorlab.analyses.identify);
    no module of the package is patched to be callable."""
    import importlib.util
    import subprocess
    import sys

    from motorlab.experiments import all_experiments

    for name in all_experiments():
        assert importlib.util.find_spec(f"motorlab.{name.replace('-', '_')}") is None, name
    code = ("import sys, types; from motorlab import feedforward, identify; import motorlab.analyses.identify; "
            "print(type(feedforward).__name__, type(identify).__name__, "
            "any(type(m) is not types.ModuleType for n, m in list(sys.modules.items()) if n.startswith('motorlab')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert out == ["function", "function", "False"]


def test_the_public_face_is_the_registry() -> None:
    """dir(motorlab) lists every experiment of the registry, the notebook's functions and the public types,
    and no helper; a name the package merely imports (``os``) is no attribute."""
    import motorlab as ml
    from motorlab.experiments import all_experiments

    names = set(dir(ml))
    assert {name.replace("-", "_") for name in all_experiments()} <= names
    assert {"analyze", "read", "describe", "FitResult", "Estimate", "Recording"} <= names
    assert not names & {"Any", "CallableModule", "annotations", "importlib", "types", "os"}
    assert sorted(ml.__all__) == sorted(names)
    for helper in ("os", "np", "Path", "sys"):
        with pytest.raises(AttributeError):
            getattr(ml, helper)
    assert ml.FitResult.__name__ == "FitResult"
