"""The bench procedures against the shipped pyvisa-sim profiles: commands, their order, safety, files."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("pyvisa_sim")

from motorlab.acquire.bench import BenchRig, Clock
from motorlab.acquire.errors import InstrumentError
from motorlab.acquire.scpi import SIM_RESOURCES, KoradSupply, RigolDP800, RigolDS1000Z, open_instrument
from motorlab.cli import main
from motorlab.errors import RigError
from motorlab.io.csv_table import read_csv
from motorlab.rig import Dynamometer


class Spy:
    """A VISA resource that records every command sent (and may corrupt one setting)."""

    def __init__(self, inner: Any, sent: list[str], rewrite: dict[str, str] | None = None):
        object.__setattr__(self, "_inner", inner)
        object.__setattr__(self, "_sent", sent)
        object.__setattr__(self, "_rewrite", rewrite or {})

    def write(self, command: str) -> Any:
        self._sent.append(command)
        return self._inner.write(self._rewrite.get(command, command))

    def query(self, command: str) -> Any:
        self._sent.append(command)
        return self._inner.query(command)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._inner, name)

    def __setattr__(self, name: str, value: Any) -> None:
        setattr(self._inner, name, value)


class FakeClock(Clock):
    """Time that passes only when the procedure sleeps; optionally a Ctrl-C after some sleeps."""

    def __init__(self, interrupt_after: int | None = None):
        self.t = 0.0
        self.sleeps = 0
        self.interrupt_after = interrupt_after
        super().__init__(now=lambda: self.t, sleep=self._sleep)

    def _sleep(self, dt: float) -> None:
        self.sleeps += 1
        if self.interrupt_after is not None and self.sleeps > self.interrupt_after:
            raise KeyboardInterrupt
        self.t += dt


def _dp800(sent: list[str], **kw: Any) -> RigolDP800:
    return RigolDP800(Spy(open_instrument(SIM_RESOURCES["dp800"], library="@sim"), sent, **kw))


def _scope(sent: list[str]) -> RigolDS1000Z:
    return RigolDS1000Z(Spy(open_instrument(SIM_RESOURCES["ds1000z"], library="@sim"), sent))


def _index(sent: list[str], command: str) -> int:
    return sent.index(command)


def test_terminal_limit_before_output_and_off_at_the_end(tmp_path: Path) -> None:
    sent: list[str] = []
    supply = _dp800(sent)
    rig = BenchRig(supply, _scope(sent), cpr=28, clock=FakeClock())
    run = rig.run("terminal", tmp_path / "t.csv", currents=[0.3, 0.4], settle=1.0, samples=3)
    assert _index(sent, ":SOUR:CURR 0.3000") < _index(sent, ":SOUR:VOLT 18.0000") < _index(sent, ":OUTP ON")
    assert _index(sent, ":OUTP ON") < _index(sent, ":SOUR:CURR 0.4000")
    assert sent[-1] == ":OUTP OFF"
    assert not supply.output_is_on()
    assert isinstance(rig, Dynamometer)  # the virtual rig's interface
    rec = read_csv(run.paths[0])
    assert rec["current"].tolist() == pytest.approx([0.512, 0.512])  # the profile's :MEAS:CURR?
    assert rec["frequency"].tolist() == pytest.approx([156.25, 156.25])  # its :MEAS:ITEM? FREQ,CHAN1
    assert rec.metadata["cpr"] == 28


def test_ctrl_c_switches_the_output_off_and_keeps_the_rows(tmp_path: Path) -> None:
    sent: list[str] = []
    supply = _dp800(sent)
    rig = BenchRig(supply, clock=FakeClock(interrupt_after=25))
    with pytest.raises(KeyboardInterrupt):
        rig.spindown(tmp_path / "s.csv", voltage=12.0, current_limit=2.0, on_time=30.0, coast_time=5.0, poll=0.5)
    assert ":OUTP ON" in sent
    assert sent[-1] == ":OUTP OFF"
    assert not supply.output_is_on()
    rows = read_csv(tmp_path / "s.csv")
    assert len(rows) >= 20  # every reading taken before the interrupt is on disk


def test_ina219_refuses_above_16_volts_before_anything_is_switched(tmp_path: Path) -> None:
    sent: list[str] = []
    rig = BenchRig(_dp800(sent), clock=FakeClock())
    with pytest.raises(RigError, match="16 V"):
        rig.spinup(tmp_path / "u.csv", voltage=18.0, current=1.0, duration=1.0)
    assert not any(c.startswith((":OUTP", ":SOUR")) for c in sent)
    assert not (tmp_path / "u.csv").exists()


def test_a_wrong_readback_leaves_the_output_off(tmp_path: Path) -> None:
    sent: list[str] = []
    supply = _dp800(sent, rewrite={":SOUR:CURR 1.0000": ":SOUR:CURR 2.0000"})  # the supply "misheard"
    rig = BenchRig(supply, clock=FakeClock())
    with pytest.raises(InstrumentError, match="reads back"):
        rig.spinup(tmp_path / "u.csv", voltage=12.0, current=1.0, duration=1.0)
    assert ":OUTP ON" not in sent
    assert sent[-1] == ":OUTP OFF"


def test_korad_sequence_and_supply_log(tmp_path: Path) -> None:
    sent: list[str] = []
    handle = open_instrument(SIM_RESOURCES["korad"], library="@sim", terminated=False)
    supply = KoradSupply(Spy(handle, sent), sleep=lambda s: None)
    assert supply.identify() == "KORADKA3005PV5.8"
    rig = BenchRig(supply, clock=FakeClock())
    run = rig.spindown(tmp_path / "k.csv", voltage=12.0, current_limit=4.0, on_time=1.0, coast_time=1.0, poll=0.1)
    assert sent.index("ISET1:4.000") < sent.index("VSET1:12.00") < sent.index("OUT1")
    assert sent[0] == "*IDN?"
    switching = [c for c in sent if c in ("OUT0", "OUT1")]
    assert switching == ["OUT0", "OUT1", "OUT0"]  # off first, on, off again
    assert sent[-1] == "IOUT1?"  # the coast is logged after the output went off
    assert sent.index("VSET1?") < sent.index("OUT1")  # read back before switching on
    rec = read_csv(run.paths[0])
    assert rec.metadata["experiment"] == "spindown-supply"
    assert rec.time[-1] == pytest.approx(2.2, abs=0.11)
    assert rec["voltage"][0] == pytest.approx(11.98)


def test_free_spinup_edges_give_the_profile_acceleration(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # The profile's waveform is channel B of a 28-count encoder spinning up at 600 rad/s² from 40 rad/s.
    out = tmp_path / "edges.csv"
    code = main(["acquire", "free-spinup", "--supply", "dp800", "--simulate", "--cpr", "28", "--timebase", "0.05",
                 "--edges", "20", "--wait", "1", "-o", str(out), "--waveform", str(tmp_path / "wave.csv")])
    assert code == 0
    capsys.readouterr()
    assert main(["analyze", "free-spinup", str(out), "--K", "0.012", "--current", "0.5", "--json"]) == 0
    alpha = json.loads(capsys.readouterr().out)["parameters"]["alpha"]
    assert alpha["value"] == pytest.approx(600.0, rel=0.02)
    assert abs(alpha["value"] - 600.0) < 3 * alpha["stderr"]
    assert (tmp_path / "wave.csv").read_text().startswith("X,CH1,Start,Increment,")


def test_cli_bad_input_one_line_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "t.csv"
    assert main(["acquire", "terminal", "--supply", "korad", "--currents", "0.3", "-o", str(out)]) == 2
    assert "--supply-resource" in capsys.readouterr().err
    assert main(["acquire", "spinup", "--supply", "korad", "--simulate", "--voltage", "20", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "16 V" in err
    assert len(err.strip().splitlines()) == 1
    assert main(["acquire", "spinup", "--supply", "korad", "--supply-resource", "ASRL/dev/nonexistent::INSTR",
                 "-o", str(out)]) == 2
    assert "cannot open" in capsys.readouterr().err
    assert not out.exists()
