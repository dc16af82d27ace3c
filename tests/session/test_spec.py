"""Session descriptions: parsing, validation with file:line messages, key line scanning."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from motorlab.errors import SessionError
from motorlab.session.spec import key_lines, load_session

GOOD = """\
# a small session
[session]
title = "NeveRest 40 fleet"
date = "2018-03-02"

[motor]
catalog = "neverest40"

[rig]
lever_arm = "20 cm"

[rig.flywheel]
disc = { radius = "75 mm", thickness = "50 mm", material = "steel" }
ratio = 25

[rig.supply]
voltage_limit = "18 V"
current_limit = "4 A"

[units.A]
label = "AM 40 A"

[units.A.lcr]
files = ["A/lcr.csv"]
frequency = "1 kHz"

[units.A.free-spinup]
files = "A/edges.csv"
current = "500 mA"

[units.B.lcr]
files = ["B/lcr.csv"]
"""


def write(tmp_path: Path, text: str, files: tuple[str, ...] = ("A/lcr.csv", "A/edges.csv", "B/lcr.csv")) -> Path:
    for name in files:
        path = tmp_path / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text("L_uH,Q,DCR_ohm\n700,2,1.7\n")
    session = tmp_path / "session.toml"
    session.write_text(text, encoding="utf-8")
    return session


def test_good_session_parses_to_si(tmp_path: Path) -> None:
    s = load_session(write(tmp_path, GOOD))
    assert s.title == "NeveRest 40 fleet"
    assert s.motor.catalog == "neverest40"
    assert s.motor.counts_per_revolution == 1120
    assert s.motor.gear_ratio == 40
    assert s.rig.lever_arm == pytest.approx(0.20)
    assert s.rig.current_limit == pytest.approx(4.0)
    # Seed 1's steel disc r = 75 mm, h = 50 mm, reflected through 25:1.
    fw = s.rig.flywheel
    assert fw is not None
    assert fw.inertia == pytest.approx(0.5 * math.pi * 0.075**4 * 7850 * 0.05)
    # The seed's "0.0124 kg·m²" is r⁴·ρ·h without the factor π/2 (the true value is 0.0195).
    assert fw.inertia == pytest.approx(0.0195, rel=0.01)
    assert fw.reflected_inertia == pytest.approx(fw.inertia * 625)
    assert list(s.units) == ["A", "B"]
    a = s.units["A"]
    assert a.display_name == "AM 40 A"
    assert list(a.experiments) == ["lcr", "free-spinup"]
    assert a.experiments["free-spinup"].settings["current"] == pytest.approx(0.5)
    assert a.experiments["lcr"].settings["frequency"] == pytest.approx(1000.0)
    assert a.experiments["lcr"].files == ((tmp_path / "A/lcr.csv").resolve(),)
    assert s.units["B"].display_name == "B"


def test_motor_by_cpr_and_inertia(tmp_path: Path) -> None:
    text = """
[motor]
name = "mystery gearmotor"
counts_per_revolution = 537.7
gear_ratio = 19.2
[rig.flywheel]
inertia = "0.0124 kg*m^2"
[units.A.lcr]
files = "A/lcr.csv"
"""
    s = load_session(write(tmp_path, text))
    assert s.motor.catalog is None
    assert s.motor.counts_per_revolution == pytest.approx(537.7)
    assert s.rig.flywheel is not None
    assert s.rig.flywheel.inertia == pytest.approx(0.0124)


def error_of(
    tmp_path: Path, text: str, files: tuple[str, ...] = ("A/lcr.csv", "A/edges.csv", "B/lcr.csv")
) -> SessionError:
    path = write(tmp_path, text, files)
    with pytest.raises(SessionError) as info:
        load_session(path)
    assert info.value.path == str(path)
    return info.value


def line_of(text: str, needle: str) -> int:
    return next(k for k, line in enumerate(text.splitlines(), start=1) if needle in line)


def test_unknown_key_names_line_and_suggests(tmp_path: Path) -> None:
    text = GOOD.replace('frequency = "1 kHz"', 'frequncy = "1 kHz"')
    err = error_of(tmp_path, text)
    assert err.line == line_of(text, "frequncy")
    assert "units.A.lcr.frequncy" in err.message
    assert "did you mean 'frequency'" in err.message


def test_unknown_experiment_suggests(tmp_path: Path) -> None:
    text = GOOD.replace("[units.A.free-spinup]", "[units.A.free-spin-up]")
    err = error_of(tmp_path, text)
    assert err.line == line_of(text, "[units.A.free-spin-up]")
    assert "did you mean 'free-spinup'" in err.message


def test_missing_file(tmp_path: Path) -> None:
    err = error_of(tmp_path, GOOD, files=("A/lcr.csv", "B/lcr.csv"))
    assert err.line == line_of(GOOD, 'files = "A/edges.csv"')
    assert "file not found: A/edges.csv" in err.message


def test_wrong_unit(tmp_path: Path) -> None:
    text = GOOD.replace('current = "500 mA"', 'current = "500 mV"')
    err = error_of(tmp_path, text)
    assert err.line == line_of(text, "500 mV")
    assert "units.A.free-spinup.current" in err.message
    assert "cannot be converted to A" in err.message


def test_wrong_unit_inside_inline_table(tmp_path: Path) -> None:
    text = GOOD.replace('radius = "75 mm"', 'radius = "75 kg"')
    err = error_of(tmp_path, text)
    assert err.line == line_of(text, "disc = ")
    assert "rig.flywheel.disc.radius" in err.message


def test_flywheel_inertia_and_disc_contradict(tmp_path: Path) -> None:
    text = GOOD.replace("ratio = 25", 'ratio = 25\ninertia = "0.0124 kg*m^2"')
    err = error_of(tmp_path, text)
    assert "both as an inertia and as a disc" in err.message
    assert err.line == line_of(text, "disc = ")


def test_current_above_supply_limit(tmp_path: Path) -> None:
    text = GOOD.replace('current = "500 mA"', 'current = "5 A"')
    err = error_of(tmp_path, text)
    assert err.line == line_of(text, 'current = "5 A"')
    assert "above the supply's current limit of 4 A" in err.message


def test_catalogue_contradiction_and_unknown_motor(tmp_path: Path) -> None:
    text = GOOD.replace('catalog = "neverest40"', 'catalog = "neverest40"\ncounts_per_revolution = 560')
    err = error_of(tmp_path, text)
    assert "contradicts the catalogue's 1120" in err.message
    assert err.line == line_of(text, "counts_per_revolution")
    text = GOOD.replace('catalog = "neverest40"', 'catalog = "neverest41"')
    err = error_of(tmp_path / "x", text)
    assert "unknown motor 'neverest41'" in err.message
    assert err.line == line_of(text, "neverest41")


def test_missing_required_setting_and_syntax_error(tmp_path: Path) -> None:
    text = GOOD.replace('current = "500 mA"\n', "")
    err = error_of(tmp_path, text)
    assert "missing key 'current'" in err.message
    assert err.line == line_of(text, "[units.A.free-spinup]")
    bad = GOOD.replace('title = "NeveRest 40 fleet"', "title = NeveRest")
    err = error_of(tmp_path / "y", bad)
    assert err.line == line_of(bad, "title = NeveRest")
    assert "invalid TOML" in err.message


def test_no_units_and_no_experiments(tmp_path: Path) -> None:
    err = error_of(tmp_path, '[motor]\ncatalog = "neverest40"\n')
    assert "no units" in err.message
    err = error_of(tmp_path / "z", '[motor]\ncatalog = "neverest40"\n[units.A]\nlabel = "x"\n')
    assert "has no experiment" in err.message
    assert err.line == 3


def test_fleet_table(tmp_path: Path) -> None:
    s = load_session(write(tmp_path, GOOD + '\n[fleet]\nthreshold = 3\nspread = { b = "10 %", R = 0.05 }\n'))
    assert s.fleet_threshold == 3
    assert s.healthy_spread == {"b": pytest.approx(0.10), "R": pytest.approx(0.05)}
    err = error_of(tmp_path / "w", GOOD + "\n[fleet]\nspread = { c = 0.1 }\n")
    assert "did you mean" in err.message or "unknown key 'c'" in err.message


def test_key_lines_scanner() -> None:
    text = '''a = 1
s = """
fake = 2
"""
[t."quoted key"]
x.y = 3
inline = { p = 1, q = "2" }
[[arr]]
k = 1
[[arr]]
k = 2
'''
    lines = key_lines(text)
    assert lines[("a",)] == 1
    assert ("fake",) not in lines
    assert lines[("t", "quoted key")] == 5
    assert lines[("t", "quoted key", "x", "y")] == 6
    assert lines[("t", "quoted key", "inline", "q")] == 7
    assert lines[("arr", "0", "k")] == 9
    assert lines[("arr", "1", "k")] == 11


def test_documented_example_is_valid(tmp_path: Path) -> None:
    # examples/session.toml uses every kind of key; with its files present it must load.
    import re

    example = Path(__file__).resolve().parents[2] / "examples" / "session.toml"
    text = example.read_text(encoding="utf-8")
    names = tuple(sorted(set(re.findall(r'"([A-C]/[\w.]+)"', text))))
    s = load_session(write(tmp_path, text, files=names))
    assert [u.display_name for u in s.units.values()] == ["AM 40 A", "AM 40 B", "AM 40 C"]
    assert len(s.units["A"].experiments["spindown"].files) == 2
    assert set(s.units["A"].experiments) == {
        "lcr",
        "spindown",
        "spinup",
        "torque",
        "terminal",
        "free-spinup",
        "identify",
    }
    assert s.fleet_threshold == 4
    assert s.healthy_spread["b"] == pytest.approx(0.25)


def test_a_file_listed_twice_is_refused_with_its_line(tmp_path: Path) -> None:
    text = GOOD.replace('files = ["B/lcr.csv"]', 'files = ["B/lcr.csv", "B/../B/lcr.csv"]')
    err = error_of(tmp_path, text)
    assert "listed twice" in str(err)
    assert err.line == text.splitlines().index('files = ["B/lcr.csv", "B/../B/lcr.csv"]') + 1


@pytest.mark.parametrize("arm", ['"15 furlongs"', '"1e308 m"', '"0.001 um"'])
def test_a_rig_quantity_beyond_any_rig_is_refused_at_load(tmp_path: Path, arm: str) -> None:
    text = GOOD.replace('lever_arm = "20 cm"', f"lever_arm = {arm}")
    err = error_of(tmp_path, text)
    assert "beyond any gearmotor rig" in str(err)
    assert err.line == text.splitlines().index(f"lever_arm = {arm}") + 1
