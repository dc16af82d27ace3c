"""Gains in the length unit of the file they were fitted from (issue 31): a SysId file in Feet gives kV per foot.

The fit runs in SI (a file in Feet or Inches logs distances: kV per metre); the analysis's JSON names the
file's unit (``details.file_units``) and ``motorlab tune`` gives the gains in it unless told otherwise, by
the exact conversion (1 ft = 0.3048 m, 1 in = 0.0254 m), never per metre under a unit that says otherwise.
"""

from __future__ import annotations

import contextlib
import io
import json
from pathlib import Path

import pytest

import motorlab.cli

#: A team's real drivetrain SysId file recorded in Feet, read in place from ../shared/data/real/sysid.
FEET = "sysid/t2168_drivetrain_0311.json"


@pytest.fixture(scope="module")
def feet_fit(tmp_path_factory: pytest.TempPathFactory, real_dir: Path) -> Path:
    """``motorlab analyze feedforward --json`` of the real Feet file, written where tune reads it."""
    found = real_dir / FEET
    out = tmp_path_factory.mktemp("feet") / "feet.json"
    buffer = io.StringIO()
    with contextlib.redirect_stdout(buffer):
        code = motorlab.cli.main(["analyze", "feedforward", str(found), "--json"])
    assert code == 0
    out.write_text(buffer.getvalue())
    return out


def _tune(capsys: pytest.CaptureFixture[str], *argv: str) -> dict:
    code = motorlab.cli.main(["tune", "velocity", "--target=wpilib", "--json", *argv])
    out, err = capsys.readouterr()
    assert code == 0, err
    return dict(json.loads(out))


def test_a_feet_file_gives_its_gains_per_foot(feet_fit: Path, capsys: pytest.CaptureFixture[str]) -> None:
    fit = json.loads(feet_fit.read_text())
    assert fit["details"]["file_units"] == {"units": "Feet", "unitsPerRotation": pytest.approx(1.0471975512),
                                            "length_unit": "ft"}
    assert fit["parameters"]["kV"]["unit"] == "V*s/m"  # the fit itself is SI
    per_foot = _tune(capsys, f"--params={feet_fit}")  # no unit asked: the file's own
    per_metre = _tune(capsys, f"--params={feet_fit}", "--units=m")
    per_inch = _tune(capsys, f"--params={feet_fit}", "--units=in")
    assert per_foot["units"]["kV"] == "V*s/ft"
    assert per_metre["units"]["kV"] == "V*s/m"
    assert per_inch["units"]["kV"] == "V*s/in"
    kv_m = per_metre["feedforward"]["kV"]
    assert kv_m == pytest.approx(fit["parameters"]["kV"]["value"], rel=1e-12)
    for name in ("kV", "kA"):
        assert per_foot["feedforward"][name] == pytest.approx(per_metre["feedforward"][name] * 0.3048, rel=1e-12)
        assert per_inch["feedforward"][name] == pytest.approx(per_metre["feedforward"][name] * 0.0254, rel=1e-12)
    # feedback gains too, and the design itself does not change with the unit
    assert per_foot["gains"]["kP"] == pytest.approx(per_metre["gains"]["kP"] * 0.3048, rel=1e-9)
    assert per_foot["response"]["rise_time"] == pytest.approx(per_metre["response"]["rise_time"], rel=1e-9)
    assert any("1 m = 3.28084 ft" in line for line in per_foot["conversion"])


@pytest.mark.parametrize(("argv", "message"), [
    (("--units=rad",), "per metre, foot or inch"),
    (("--units=rotations",), "per metre, foot or inch"),
    (("--wheel-radius=3 in",), "leave the wheel radius out"),
    (("--target=roadrunner", "--cpr=2048"), "counts the motor's turns"),
])
def test_a_model_of_distances_refuses_angles_in_one_line(feet_fit: Path, capsys: pytest.CaptureFixture[str],
                                                          argv: tuple[str, ...], message: str) -> None:
    code = motorlab.cli.main(["tune", "velocity", f"--params={feet_fit}", "--target=wpilib", *argv])
    err = capsys.readouterr().err
    assert code == 2
    assert message in err
    assert len(err.strip().splitlines()) == 1


def test_an_inches_result_and_a_rotations_result_default_to_their_units(tmp_path: Path,
                                                                       capsys: pytest.CaptureFixture[str]) -> None:
    """The unit read from the result: Inches → V·s/in by 0.0254 exactly; Rotations → V·s/rot (2π per rotation)."""
    def result(kv_unit: str, units: str, length: str) -> Path:
        doc = {"experiment": "feedforward",
               "parameters": {"kS": {"value": 0.2, "stderr": 0.01, "unit": "V"},
                              "kV": {"value": 2.5, "stderr": 0.01, "unit": kv_unit},
                              "kA": {"value": 0.4, "stderr": 0.01, "unit": kv_unit.replace("*s/", "*s^2/")}},
               "details": {"file_units": {"units": units, "unitsPerRotation": 1.0, "length_unit": length}}}
        path = tmp_path / f"{units}.json"
        path.write_text(json.dumps(doc))
        return path

    inches = _tune(capsys, f"--params={result('V*s/m', 'Inches', 'in')}")
    assert inches["units"]["kV"] == "V*s/in"
    assert inches["feedforward"]["kV"] == pytest.approx(2.5 * 0.0254, rel=1e-12)
    rotations = _tune(capsys, f"--params={result('V*s/rad', 'Rotations', 'rotations')}")
    assert rotations["units"]["kV"] == "V*s/rot"
    assert rotations["feedforward"]["kV"] == pytest.approx(2.5 * 2 * 3.141592653589793, rel=1e-12)
    plain = _tune(capsys, "--kv=2.5", "--ka=0.4")  # no file: radians, as before
    assert plain["units"]["kV"] == "V*s/rad"
