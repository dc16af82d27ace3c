"""Encoders with a non-integer count per output revolution (goBILDA 5203 19.2:1: 537.7) end to end."""

from __future__ import annotations

import json

from motorlab import cli
from motorlab.rig import VirtualRig


def test_identify_with_fractional_cpr(tmp_path, capsys):
    rig = VirtualRig("gobilda5202_19", unit_seed=0, noise_seed=3)
    run = rig.transient(tmp_path / "transient.csv", duration=2.0)
    assert rig.motor.cpr == 537.7
    code = cli.main(["analyze", "identify", str(run.paths[0]), "--cpr", "537.7", "--json"])
    assert code == 0
    out = json.loads(capsys.readouterr().out)["parameters"]
    for name in ("K", "R", "J"):
        truth = run.truth["params"][name]
        est = out[name]
        assert abs(est["value"] - truth) < 4 * est["stderr"], (name, est, truth)
