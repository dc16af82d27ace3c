"""Quantities given by people become SI floats, with clear errors otherwise."""

from __future__ import annotations

import math

import pytest

from motorlab.errors import OptionError
from motorlab.units import format_unit, parse_quantity


@pytest.mark.parametrize(
    ("text", "unit", "expected"),
    [
        ("0.0124 kg*m^2", "kg*m^2", 0.0124),
        ("130 rpm", "rad/s", 130 * 2 * math.pi / 60),
        # Seed 1's hand conversion: 400 in·oz = 2.83 N·m (ounce-force inch).
        ("400 in*oz", "N*m", 400 * 0.0254 * 0.028349523125 * 9.80665),
        ("700 uH", "H", 700e-6),
        ("250 mA", "A", 0.25),
        ("1 kHz", "Hz", 1000.0),
        ("7.8", "kg*m^2", 7.8),
        (0.5, "A", 0.5),
        ("150 g", "N", 0.150 * 9.80665),
    ],
)
def test_parses_quantities_to_si(text, unit, expected):
    assert parse_quantity(text, unit) == pytest.approx(expected, rel=1e-9)


def test_seed_worked_conversion_of_stall_torque():
    assert parse_quantity("400 in*oz", "N*m") == pytest.approx(2.83, abs=0.01)


@pytest.mark.parametrize(
    ("text", "unit"),
    [("12 furlongs", "kg*m^2"), ("3 V", "A"), ("abc", "A"), ("nan", "A"), ("inf A", "A"), (True, "A")],
)
def test_rejects_wrong_units_and_garbage(text, unit):
    with pytest.raises(OptionError) as err:
        parse_quantity(text, unit, name="--current")
    assert "\n" not in str(err.value)


def test_format_unit_for_people():
    assert format_unit("N*m*s/rad") == "N·m·s/rad"
    assert format_unit("kg*m^2") == "kg·m²"
    assert format_unit("ohm") == "Ω"


def test_rotation_is_a_unit_as_wpilib_writes_it():
    assert parse_quantity("2 rotations", "rad") == pytest.approx(4 * math.pi)
    assert parse_quantity("1 V*s/rotation", "V*s/rad") == pytest.approx(1 / (2 * math.pi))


def test_the_registry_keeps_its_definitions_in_a_cache_that_heals(tmp_path, monkeypatch: pytest.MonkeyPatch) -> None:
    """pint's parsed definitions are kept on disk (0.05 s to set up instead of 0.5 s); a cache that cannot be read
    (a pickle cut short while another process wrote it) or written (a file where its folder should be) leaves a
    registry that converts the same, and a cache that cannot be read is removed so that the next start rebuilds it."""
    from motorlab import units

    folder = tmp_path / "cache" / "pint"
    monkeypatch.setattr(units, "_cache_folder", lambda: folder)
    speed = "5800 rpm"  # a free speed
    expected = units._new_registry().Quantity(speed).to("rad/s").magnitude
    pickles = sorted(folder.glob("*.pickle"))
    assert pickles, "nothing was cached"
    assert units._new_registry().Quantity(speed).to("rad/s").magnitude == expected  # read from the cache
    for path in pickles:
        path.write_bytes(path.read_bytes()[:100])
    assert units._new_registry().Quantity(speed).to("rad/s").magnitude == expected
    assert not folder.exists()
    (tmp_path / "file").write_text("a file, not a folder")
    monkeypatch.setattr(units, "_cache_folder", lambda: tmp_path / "file" / "pint")
    assert units._new_registry().Quantity(speed).to("rad/s").magnitude == expected
