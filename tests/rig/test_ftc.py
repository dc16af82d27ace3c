"""FTC sensors of the virtual rig: hub velocity, bulk-read loop, battery sag, INA219 averaging, LC filter."""

from __future__ import annotations

import math

import numpy as np
import pytest

from motorlab.errors import RigError
from motorlab.rig.ftc import Battery, BulkReadLoop, HubEncoder, LCFilter, wrap_int16
from motorlab.rig.instruments import INA219


def test_hub_velocity_is_a_wrapping_multiple_of_twenty():
    enc = HubEncoder(8192)
    speed = 60.0  # rad/s: 78 000 ticks/s, beyond a 16-bit register

    def angle(t):
        return speed * np.asarray(t)

    t = np.linspace(0.1, 1.0, 50)
    true = enc.true_velocity(t, angle)
    reported = enc.velocity(t, angle)
    assert np.all(np.mod(true, 20) == 0)
    assert np.all(np.abs(reported) <= 2**15)
    assert np.median(true) == pytest.approx(speed * 8192 / (2 * math.pi), rel=1e-3)
    np.testing.assert_array_equal(reported, wrap_int16(true))
    assert np.all(reported != true)


def test_bulk_read_loop_jitters_between_10_and_40_ms():
    loop = BulkReadLoop()
    starts = loop.starts(20.0, np.random.default_rng(1))
    periods = np.diff(starts)
    assert periods.min() >= 0.010 - 1e-12
    assert periods.max() <= 0.040 + 1e-12
    assert np.std(periods) > 2e-3
    sched = loop.schedule(starts, 4)
    assert np.all(sched["bulk"] > sched["voltage"])
    assert np.all(sched["voltage"] > sched["power"][:, -1])


def test_battery_sags_with_current():
    bat = Battery(open_circuit=13.0, internal_resistance=0.1, drift=0.0, other_current=0.0)
    assert bat.bus_voltage(np.array([0.0]), np.array([20.0]))[0] == pytest.approx(11.0)


def test_ina219_128_sample_averaging_lags_about_69_ms():
    sensor = INA219(averaging=128)
    assert sensor.result_period == pytest.approx(0.0681, abs=1e-4)
    grid = np.arange(0.0, 2.0, 1e-4)
    ramp = 5.0 * grid  # a ramp shows the lag as an offset
    times = np.sort(np.random.default_rng(2).uniform(0.5, 1.9, 400))
    lag = times - sensor.conversion_average(times, grid, ramp) / 5.0
    assert np.mean(lag) == pytest.approx(0.0681, rel=0.1)  # T/2 of averaging + T/2 of waiting on average
    assert np.max(lag) <= 1.5 * 0.0681 + 1e-9
    assert np.min(lag) >= 0.5 * 0.0681 - 1e-9
    with pytest.raises(RigError, match="16 V"):
        sensor.check_supply(18.0)


def test_lc_filter_passes_dc_and_removes_commutator_noise():
    f = LCFilter()
    assert f.resonances()[0] == pytest.approx(1 / (2 * math.pi * math.sqrt(f.L1 * f.C1)), rel=0.5)
    t = np.arange(0.0, 0.2, 2e-6)
    noisy = 12.0 + 0.5 * np.sin(2 * math.pi * 5000 * t)  # brush noise at 5 kHz
    out = f.apply(t, noisy)
    tail = out[t > 0.1]
    assert np.mean(tail) == pytest.approx(12.0, abs=0.01)
    assert np.std(tail) < 0.02 * 0.5


def test_virtual_rig_ina219_averaging_lags_the_bus_voltage(tmp_path):
    import dataclasses

    from motorlab.io import read_ftc_log
    from motorlab.rig import Instruments, VirtualRig

    quiet = INA219(bus_noise=0.0, current_noise=0.0)
    logs = {}
    for n in (1, 128):
        ins = dataclasses.replace(Instruments(), ina219=dataclasses.replace(quiet, averaging=n))
        rig = VirtualRig("neverest40", unit_seed=1, noise_seed=3, instruments=ins)
        path = tmp_path / f"avg{n}.txt"
        rig.spindown(path, on_time=3.0, coast_time=2.0)
        logs[n] = read_ftc_log(path)
    plain, averaged = logs[1], logs[128]
    np.testing.assert_array_equal(plain.time, averaged.time)
    # the relay opens at 3 s: the bus voltage falls to the back-EMF; the averaged register follows late
    after = (plain.time > 3.2) & (plain.time < 3.3)
    assert np.all(averaged["voltage"][after] >= plain["voltage"][after] - 0.01)
    assert np.mean(averaged["voltage"][after] - plain["voltage"][after]) > 0.05


def test_virtual_rig_lc_filter_quiets_the_bus_voltage_trace(tmp_path):
    """The seed's LC filter as an option of the rig's INA219: commutation noise down, DC kept."""
    import dataclasses

    from motorlab.io import read_ftc_log
    from motorlab.rig import Instruments, VirtualRig

    logs = {}
    for name, bus_filter in (("bare", None), ("filtered", LCFilter())):
        ins = dataclasses.replace(Instruments(), ina219=dataclasses.replace(INA219(), bus_filter=bus_filter))
        rig = VirtualRig("neverest40", unit_seed=1, noise_seed=4, instruments=ins)
        path = tmp_path / f"{name}.txt"
        rig.spindown(path, on_time=3.0, coast_time=1.0)
        logs[name] = read_ftc_log(path)
    bare, filtered = logs["bare"], logs["filtered"]
    on = (bare.time > 0.5) & (bare.time < 2.9)  # on the supply, spinning up slowly

    def noise(v):  # sample-to-sample noise, blind to the slow rise
        return np.std(np.diff(v[on])) / math.sqrt(2)

    assert noise(bare["voltage"]) > 0.05  # the seed's "extremely noisy" bus reading
    assert noise(filtered["voltage"]) < 0.3 * noise(bare["voltage"])
    assert np.mean(filtered["voltage"][on]) == pytest.approx(np.mean(bare["voltage"][on]), abs=0.03)
    # on the bus itself: the relay's step rings through the filter (its resonance) and settles
    f = LCFilter()
    t = np.arange(0.0, 0.1, 1e-5)
    out = INA219(bus_filter=f).bus_input(t, np.where(t < 0.02, 12.0, 10.0))
    assert out[t > 0.02].min() < 10.0 - 0.2  # overshoot below the new level
    assert out[-1] == pytest.approx(10.0, abs=0.01)
