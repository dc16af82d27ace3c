"""The motor catalogue: loading, physical consistency, WPILib derivations, lookup errors, CLI."""

from __future__ import annotations

import json
import math

import pytest

import motorlab.cli as cli
from motorlab.catalog import Motor, list_motors
from motorlab.errors import InputError, OptionError

RPM = 2 * math.pi / 60
IN_OZ = 0.0254 * 0.028349523125 * 9.80665  # [N·m] per in·oz (force ounce = mass ounce × g0)

MOTORS = list_motors()


@pytest.fixture
def run_cli():
    """``motorlab.cli.main``, the console script's entry point."""
    return cli.main


def test_catalogue_has_the_issue_motors():
    keys = {m.key for m in MOTORS}
    expected = {"neverest20", "neverest40", "neverest60", "neverest37", "corehex", "hdhex20", "hdhex40"}
    assert expected | {"matrix12v", "gobilda5202_19"} <= keys
    assert sum(k.startswith("gobilda5202_") for k in keys) >= 5


@pytest.mark.parametrize("motor", MOTORS, ids=lambda m: m.key)
def test_every_entry_is_physically_consistent(motor):
    assert motor.cpr > 0
    assert motor.gear_ratio > 0
    assert 0 < motor.free_current < motor.stall_current
    assert motor.resistance > 0
    # Free speed below the no-load limit V/K of an ideal motor with that K.
    assert motor.free_speed < motor.nominal_voltage / motor.back_emf_constant
    # The gearbox cannot deliver more than the electromagnetic torque: Kt ≤ Ke.
    assert 0.2 < motor.gearbox_efficiency_at_stall <= 1.0
    # Every figure has a source, and every unconfirmed field is a real field.
    for name in ("gear_ratio", "cpr", "nominal_voltage", "free_speed", "stall_torque", "stall_current"):
        assert motor.sources.get(name), f"{motor.key}: no source for {name}"
    for name in motor.unconfirmed:
        assert name in motor.sources
    # Counts per output revolution agree with motor counts × ratio where both are known.
    if motor.motor_cpr is not None:
        assert motor.cpr == pytest.approx(motor.motor_cpr * motor.gear_ratio, rel=0.01)
    if motor.motor_free_speed is not None:
        assert motor.free_speed * motor.gear_ratio == pytest.approx(motor.motor_free_speed, rel=0.01)


@pytest.mark.parametrize("motor", MOTORS, ids=lambda m: m.key)
def test_nominal_params_reproduce_the_data_sheet(motor):
    p = motor.nominal_params()
    v = motor.nominal_voltage
    assert pytest.approx(motor.back_emf_constant) == p.K
    assert pytest.approx(v / motor.stall_current) == p.R
    # The model's free speed, free current and stall current are the sheet's exactly.
    assert p.free_speed(v) == pytest.approx(motor.free_speed, rel=1e-9)
    assert p.free_current(v) == pytest.approx(motor.free_current, rel=1e-9)
    assert p.stall_current(v) == pytest.approx(motor.stall_current, rel=1e-12)
    # Half the free-running loss viscous, half Coulomb; the assumed τm is met.
    assert p.b * motor.free_speed == pytest.approx(p.Tf, rel=1e-9)
    assert p.mechanical_time_constant == pytest.approx(0.030, rel=1e-9)
    assert 1e-4 < p.L / p.R < 2e-3


def test_neverest40_derivations_by_hand():
    m = Motor.from_catalog("neverest40")
    assert m.free_speed == pytest.approx(160 * RPM)
    assert m.stall_torque == pytest.approx(350 * IN_OZ, rel=1e-6)
    R = 12 / 11.5
    assert m.resistance == pytest.approx(R)
    assert m.torque_constant == pytest.approx(350 * IN_OZ / 11.5, rel=1e-6)
    assert m.back_emf_constant == pytest.approx((12 - R * 0.4) / (160 * RPM))
    # Seed 1's spin-down Ke for AM 40 A/B/C was 0.705-0.763 V·s/rad: the sheet's Ke is close.
    assert 0.65 < m.back_emf_constant < 0.8


def test_gobilda_torque_in_kgf_cm():
    m = Motor.from_catalog("gobilda5202_19")
    assert m.stall_torque == pytest.approx(24.3 * 0.0980665, rel=1e-6)
    assert m.cpr == pytest.approx(537.7)


def test_nominal_params_options():
    m = Motor.from_catalog("neverest60")
    p = m.nominal_params(mechanical_time_constant=0.02, viscous_fraction=1.0)
    assert p.Tf == 0.0
    assert p.mechanical_time_constant == pytest.approx(0.02)
    with pytest.raises(OptionError):
        m.nominal_params(viscous_fraction=1.5)
    with pytest.raises(OptionError):
        m.nominal_params(mechanical_time_constant=-1.0)


@pytest.mark.parametrize(
    ("name", "key"),
    [("NeveRest 40", "neverest40"), ("neverest-60", "neverest60"), ("Orbital 3.7", "neverest37"),
     ("REV Core Hex", "corehex"), ("goBILDA 5202_19", "gobilda5202_19"), ("HDHEX40", "hdhex40")],
)
def test_from_catalog_accepts_names(name, key):
    assert Motor.from_catalog(name).key == key


def test_names_are_unambiguous():
    from motorlab.catalog import _normalize

    seen: dict[str, str] = {}
    for m in MOTORS:
        for n in {_normalize(x) for x in (m.key, m.name, *m.aliases)}:
            assert seen.setdefault(n, m.key) == m.key, f"{n!r} names {seen[n]} and {m.key}"


def test_from_catalog_unknown_lists_valid_keys():
    with pytest.raises(OptionError, match="neverest40") as info:
        Motor.from_catalog("NeveRest 45")
    assert "unknown motor" in str(info.value)


def test_bad_catalogue_files(tmp_path):
    good = '[m]\nname = "x"\ngear_ratio = 10\ncpr = 280\nnominal_voltage = "12 V"\nfree_speed = "100 rpm"\n'
    good += 'stall_torque = "1 N*m"\nstall_current = "5 A"\nfree_current = "0.2 A"\n'
    path = tmp_path / "motors.toml"
    path.write_text(good)
    (m,) = list_motors(path=path)
    assert m.free_speed == pytest.approx(100 * RPM)
    cases = {
        "unknown field": good + "colour = 'red'\n",
        "missing field": good.replace('cpr = 280\n', ""),
        "cannot be converted": good.replace('"1 N*m"', '"1 V"'),
        "must be positive": good.replace('"5 A"', '"-5 A"'),
        "smaller than the stall": good.replace('"0.2 A"', '"6 A"'),
        "not a valid catalogue": good + "[[[",
    }
    for message, text in cases.items():
        path.write_text(text)
        with pytest.raises(InputError, match=message) as info:
            list_motors(path=path)
        assert str(path) in str(info.value)


def test_cli_lists_all_motors(run_cli, capsys):
    assert run_cli(["motors"]) == 0
    out = capsys.readouterr().out
    for m in MOTORS:
        assert m.key in out


def test_cli_one_motor_json(run_cli, capsys):
    assert run_cli(["motors", "NeveRest 60", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["key"] == "neverest60"
    assert data["nominal_params"]["K"]["unit"] == "V*s/rad"
    assert data["figures"]["free speed"]["value"] == pytest.approx(105 * RPM)
    assert "free_current" in data["unconfirmed"]


def test_cli_one_motor_table(run_cli, capsys):
    assert run_cli(["motors", "corehex", "--voltage", "9 V"]) == 0
    out = capsys.readouterr().out
    assert "Model figures at 9 V" in out
    assert "Kt = τ_stall/I_stall" in out


def test_cli_unknown_motor_exits_2(run_cli, capsys):
    assert run_cli(["motors", "nope"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("motorlab: error: unknown motor 'nope'")
    assert err.count("\n") == 1


def test_cli_bad_voltage_exits_2(run_cli, capsys):
    with pytest.raises(SystemExit) as info:
        run_cli(["motors", "neverest40", "--voltage", "-3 V"])
    assert info.value.code == 2
    assert "must be positive" in capsys.readouterr().err
