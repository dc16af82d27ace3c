"""The experiments' descriptions: everything generated from them agrees with them."""

from __future__ import annotations

import importlib
import json
import subprocess
import sys
from pathlib import Path

import pytest

import motorlab as ml
from motorlab.cli import main
from motorlab.errors import OptionError
from motorlab.experiments import Experiment, all_experiments, get, schema

ROOT = Path(__file__).resolve().parents[2]


def test_every_module_describes_one_experiment_whose_analysis_exists() -> None:
    experiments = all_experiments()
    assert set(experiments) == {"spindown", "spinup", "free-spinup", "terminal", "lcr", "torque", "amplifier",
                                "tachometer", "pulse", "identify", "feedforward", "curve", "stall"}
    for name, exp in experiments.items():
        assert isinstance(exp, Experiment)
        module, function = exp.analysis.split(":")
        assert callable(getattr(importlib.import_module(module), function)), name
        assert exp.session is not None
        assert exp.shaft
        keys = [opt.key for opt in exp.options]
        assert len(keys) == len(set(keys)), f"{name}: two options with one name"


def test_the_schema_is_json() -> None:
    text = json.dumps(schema(), allow_nan=False)
    back = json.loads(text)
    spindown = {opt["name"]: opt for opt in back["spindown"]["options"]}
    assert spindown["inertia"]["unit"] == "kg*m^2"
    assert spindown["guard"]["default"] == pytest.approx(0.1)
    assert back["free-spinup"]["session"]["settings"][0] == {
        "name": "current", "kind": "A", "help": "constant current driving the free motor (required)", "required": True,
    }


def test_copied_constants_agree_with_the_analyses() -> None:
    from motorlab.analyses import lcr, pulse
    from motorlab.analyses.feedforward import MECHANISMS
    from motorlab.experiments import feedforward as ff_exp
    from motorlab.experiments import lcr as lcr_exp
    from motorlab.experiments import pulse as pulse_exp
    from motorlab.io.frc_json import UNITS

    assert lcr_exp.OUTLIER_Z == lcr.OUTLIER_Z
    assert pulse_exp.DEFAULT_SKIP == pulse.DEFAULT_SKIP
    assert pulse_exp.FRICTION_MODELS == pulse.FRICTION_MODELS
    assert ff_exp.MECHANISMS == MECHANISMS
    assert ff_exp.UNIT_CHOICES == tuple(u.title() for u in UNITS)


def test_docs_option_tables_are_current() -> None:
    done = subprocess.run([sys.executable, str(ROOT / "scripts" / "experiment_docs.py"), "--check"],
                          capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr


def test_cli_and_notebook_come_from_the_descriptions(capsys: pytest.CaptureFixture[str]) -> None:
    for name, exp in all_experiments().items():
        with pytest.raises(SystemExit):
            main(["analyze", name, "--help"])
        text = capsys.readouterr().out
        for opt in exp.options:
            assert f"--{opt.name}" in text, (name, opt.name)
        assert callable(getattr(ml, name.replace("-", "_")))


def test_option_values_convert_units_and_check_signs() -> None:
    exp = get("spindown")
    values = exp.values({"inertia": "7.8 g*m^2", "cpr": 560, "material": "aluminium"})
    assert values["inertia"] == pytest.approx(7.8e-3)
    assert values["cpr"] == 560
    assert values["guard"] == pytest.approx(0.1)
    with pytest.raises(OptionError, match="inertia_stderr"):
        exp.values({"inertia_stderr": "-1 kg*m^2"})
    with pytest.raises(OptionError, match="material"):
        exp.values({"material": "unobtainium"})
    identify = get("identify")
    assert identify.values({})["use_current"] is True
    assert identify.values({"no_current": True})["use_current"] is False
    assert identify.values({"use_current": False})["use_current"] is False
    pulse = get("pulse")
    assert pulse.values({"K": 0.03})["torque_constant"] == pytest.approx(0.03)
    with pytest.raises(OptionError, match="same option"):
        pulse.values({"K": 0.03, "Km": 0.03})


def test_session_and_characterize_tables_come_from_the_descriptions() -> None:
    from motorlab.session.characterize import ADAPTERS, CONTRIBUTIONS, ORDER, SHAFTS
    from motorlab.session.simulated import SIMULATED_EXPERIMENTS
    from motorlab.session.spec import EXPERIMENT_SETTINGS, LOADED_EXPERIMENTS, REQUIRED_SETTINGS

    experiments = all_experiments()
    assert ORDER[:2] == ("lcr", "spindown")  # sources of K first
    assert ORDER.index("spindown") < ORDER.index("spinup")  # the spin-up takes the spin-down's friction
    assert set(ADAPTERS) == set(experiments) == set(EXPERIMENT_SETTINGS) == set(CONTRIBUTIONS) == set(SHAFTS)
    assert LOADED_EXPERIMENTS == {"spindown", "spinup", "torque"}
    assert REQUIRED_SETTINGS == {"free-spinup": ("current",)}
    assert [e[0] for e in SIMULATED_EXPERIMENTS][:3] == ["lcr", "spindown", "torque"]


def test_whole_number_options_take_digits_only() -> None:
    from motorlab.experiments import Option

    count = Option("count", kind="int", positive=True)
    assert count.convert("12") == 12
    assert count.convert(4.0) == 4
    for bad in ("1_0", "x", 2.5, True, float("inf")):
        with pytest.raises(OptionError, match="not a whole number"):
            count.convert(bad)
    with pytest.raises(OptionError, match="must be positive"):
        count.convert("-1")


def test_every_option_has_a_label_in_words_and_every_report_a_name() -> None:
    from motorlab.experiments._commands import command_options
    from motorlab.glossary import PARAMETERS

    options = [opt for exp in all_experiments().values() for opt in exp.options]
    options += [*command_options("tune"), *command_options("characterize")]
    for opt in options:
        assert opt.label, opt.name
        assert opt.label[0].isupper(), opt.label
        assert "--" not in opt.label + opt.help, opt.name
        assert "(default" not in opt.help, opt.name  # the CLI appends the default; the page shows it
    for exp in all_experiments().values():
        assert exp.title, exp.name
        missing = [k for k in (*exp.reports, *exp.contributes, *exp.contributes.values()) if k not in PARAMETERS]
        assert not missing, (exp.name, missing)
    assert "(default 0.1)" in get("spindown").option("guard").cli_help
    assert "[s]" in get("spindown").option("guard").cli_help
