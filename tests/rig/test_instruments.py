"""Instrument models: quantisation, noise statistics, ranges and refusals."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from motorlab.errors import OptionError, RigError
from motorlab.rig.instruments import (
    INA219,
    Amplifier,
    Encoder,
    LCRMeter,
    LoggingLoop,
    OpticalTachometer,
    Oscilloscope,
    PowerSupply,
    Scale,
    Tachometer,
    quantize,
)
from motorlab.units import STANDARD_GRAVITY


def _is_multiple(values: np.ndarray, step: float) -> bool:
    return bool(np.allclose(values / step, np.round(values / step), atol=1e-6))


def test_quantize_prints_cleanly() -> None:
    q = quantize(np.array([0.30000001, 1.2345678, -0.0061]), 1e-3)
    assert [repr(float(v)) for v in q] == ["0.3", "1.235", "-0.006"]


@pytest.mark.parametrize("seed", [1, 2])
def test_ina219_bus_voltage_lsb_and_noise(seed: int) -> None:
    ina = INA219()
    rng = np.random.default_rng(seed)
    true = np.full(20000, 6.5)
    read = ina.read_bus_voltage(true, rng)
    assert _is_multiple(read, 4e-3)
    assert abs(read.mean() - 6.5) < 4 * ina.bus_noise / math.sqrt(read.size)
    assert read.std() == pytest.approx(ina.bus_noise, rel=0.05)


def test_ina219_bus_voltage_is_unsigned_and_clipped() -> None:
    ina = replace(INA219(), bus_noise=0.0)
    read = ina.read_bus_voltage(np.array([-3.0, 0.0, 20.0]), np.random.default_rng(0))
    assert list(read) == [0.0, 0.0, 16.0]


@pytest.mark.parametrize("seed", [3, 4])
def test_ina219_current_lsb_noise_and_range(seed: int) -> None:
    ina = INA219()
    assert ina.current_lsb == pytest.approx(1e-4)
    assert ina.current_range == pytest.approx(3.2)
    rng = np.random.default_rng(seed)
    read = ina.read_current(np.full(20000, 1.25), rng)
    assert _is_multiple(read, 1e-4)
    assert read.mean() == pytest.approx(1.25 + ina.current_offset, abs=4 * ina.current_noise / math.sqrt(read.size))
    assert read.std() == pytest.approx(ina.current_noise, rel=0.05)
    clipped = ina.read_current(np.array([5.0, -5.0]), rng)
    assert list(clipped) == [3.2, -3.2]


def test_ina219_refuses_more_than_16_volts() -> None:
    ina = INA219()
    ina.check_supply(16.0)
    with pytest.raises(RigError, match="16 V"):
        ina.check_supply(16.5)


def test_encoder_counts_floor_and_channel_b_edges() -> None:
    enc = Encoder(1120)
    step = 2 * math.pi / 1120
    assert list(enc.counts(np.array([0.0, 0.999 * step, step, 2.5 * step, -0.5 * step]))) == [0, 0, 1, 2, -1]
    angles = enc.channel_b_rising_angles(0.0, 40 * step)
    counts_at = enc.counts(angles)
    assert list(counts_at) == [2, 6, 10, 14, 18, 22, 26, 30, 34, 38]
    # Just before each edge channel B is low, at the edge it is high.
    assert np.all(enc.channel_b_level(angles - 1e-3 * step) == 0.0)
    assert np.all(enc.channel_b_level(angles) > 0.0)
    assert enc.channel_frequency(2 * math.pi) == pytest.approx(1120 / 4)
    with pytest.raises(OptionError):
        Encoder(0)


@pytest.mark.parametrize("seed", [5, 6])
def test_logging_loop_period_and_jitter(seed: int) -> None:
    loop = LoggingLoop()
    times = loop.times(200.0, np.random.default_rng(seed))
    gaps = np.diff(times)
    assert np.all(gaps >= loop.period)
    expected = loop.period + loop.extra_delay + loop.stall_probability * loop.stall_delay
    assert gaps.mean() == pytest.approx(expected, rel=0.01)
    assert loop.first_sample[0] <= times[0] <= loop.first_sample[1]
    assert times[-1] <= 200.0


def test_supply_checks_and_display() -> None:
    supply = PowerSupply()
    supply.check(12.0, 4.0)
    with pytest.raises(OptionError):
        supply.check(31.0, 1.0)
    with pytest.raises(OptionError):
        supply.check(12.0, 0.0)
    shown = supply.display_current(np.full(1000, 2.0), np.random.default_rng(0))
    assert _is_multiple(shown, 1e-3)
    assert np.all(np.abs(shown - 2.0) <= 2.0 * supply.current_accuracy + 0.5e-3 + 1e-12)


def test_scale_reads_torque_over_arm_and_overloads() -> None:
    scale = Scale()
    rng = np.random.default_rng(7)
    torque = np.full(4000, 1.5)
    read = scale.read(torque, 0.15, rng)
    assert _is_multiple(read, 1e-3)
    assert read.mean() == pytest.approx(1.5 / (STANDARD_GRAVITY * 0.15), abs=1e-4)
    with pytest.raises(RigError, match="overload"):
        scale.read(np.array([10.0]), 0.15, rng)


def test_lcr_quality_factor_closed_form() -> None:
    meter = replace(LCRMeter(), inductance_scatter=0.0, quality_scatter=0.0, resistance_noise=0.0)
    read = meter.read(np.array([700e-6]), np.array([2.2]), np.array([1.9]), np.random.default_rng(0))
    assert read["inductance"][0] == pytest.approx(700e-6)
    assert read["quality_factor"][0] == pytest.approx(round(2 * math.pi * 1000 * 700e-6 / 2.2, 2))
    assert read["dc_resistance"][0] == pytest.approx(1.9)


@pytest.mark.parametrize("seed", [8, 9])
def test_scope_cursor_resolution_and_scatter(seed: int) -> None:
    scope = Oscilloscope(timebase=0.05)
    assert scope.cursor_step == pytest.approx(1e-3)
    true = np.linspace(0.0, 0.5, 5000)
    read = scope.cursor_times(true, np.random.default_rng(seed))
    assert _is_multiple(read, 1e-3)
    expected_sd = math.sqrt((scope.cursor_jitter * 1e-3) ** 2 + (1e-3) ** 2 / 12)
    assert (read - true).std() == pytest.approx(expected_sd, rel=0.06)
    freq = scope.measure_frequency(np.array([123.4567, 0.0]), np.random.default_rng(seed))
    assert freq[0] == pytest.approx(123.4567, rel=1e-3)
    assert freq[1] == 0.0


def test_amplifier_and_tachometers() -> None:
    amp = Amplifier()
    assert list(amp.current(np.array([0.0, 1.0, 10.0]))) == pytest.approx([amp.offset, amp.gain + amp.offset, 5.0])
    tach = Tachometer()
    rng = np.random.default_rng(10)
    position = np.linspace(0.0, 200 * math.pi, 50000)
    volts = tach.voltage(np.full(position.size, 10.0), position, rng)
    assert volts.mean() == pytest.approx(tach.gain * 10.0, rel=1e-3)  # ripple averages out over whole turns
    optical = OpticalTachometer()
    rpm = optical.read_rpm(np.full(2000, 10.0), rng)
    assert rpm.mean() == pytest.approx(10.0 * 60 / (2 * math.pi), rel=1e-4)
