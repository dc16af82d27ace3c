"""One analysis path per experiment: a session's answer is the command's answer for the same files and options.

Every experiment of a simulated session is run both ways: inside ``characterize`` (its description's
``session`` turning the session's table and the unit's earlier results into option values) and as the
notebook call ``ml.analyze(name, files, **options)`` with those options typed out, as a person would give
them to ``motorlab analyze``. The parameters, their standard errors and the warnings must be the same.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import pytest

import motorlab as ml
from motorlab import experiments
from motorlab.session.characterize import characterize
from motorlab.session.simulated import write_simulated_session
from motorlab.session.spec import load_session


def _given(monkeypatch: pytest.MonkeyPatch) -> dict[str, experiments.FromSession]:
    """Capture what each experiment's description hands its run in a session."""
    captured: dict[str, experiments.FromSession] = {}
    original = experiments.Experiment.in_session

    def spy(self: experiments.Experiment, ctx: Any) -> Any:
        assert self.session is not None
        captured[self.name] = self.session(ctx)
        return original(self, ctx)

    monkeypatch.setattr(experiments.Experiment, "in_session", spy)
    return captured


def _same(a: float, b: float) -> bool:
    return (math.isnan(a) and math.isnan(b)) or a == pytest.approx(b, rel=1e-9, abs=1e-15)


def test_every_experiment_answers_the_same_in_a_session_and_as_a_command(tmp_path: Path,
                                                                         monkeypatch: pytest.MonkeyPatch) -> None:
    from motorlab.session import characterize as characterize_module

    captured = _given(monkeypatch)
    monkeypatch.setattr(characterize_module, "ADAPTERS", {
        name: (lambda ctx, exp=exp: exp.in_session(ctx)) for name, exp in experiments.all_experiments().items()
        if exp.session is not None
    })
    write_simulated_session("neverest40", out_dir=tmp_path, units=1, seed=5)
    session = load_session(tmp_path / "session.toml")
    unit = characterize(session, control=False, figures=False).units["A"]
    spec = session.units["A"]
    assert unit.fits, unit.failures
    compared = []
    for name, fit in unit.fits.items():
        given = captured[name]
        options = {key: value for key, value in given.options.items() if value is not None}
        if given.fits or given.known:
            continue  # an earlier fit handed over whole (the spin-up's spin-down): no option says it
        files = [str(p) for p in spec.experiments[name].files]
        command = ml.analyze(name, files, **options)
        assert set(command.parameters) == set(fit.parameters), name
        for key, est in fit.parameters.items():
            other = command.parameters[key]
            assert _same(est.value, other.value), (name, key, est, other)
            assert _same(est.stderr, other.stderr), (name, key, est, other)
        session_only = [w for w in fit.warnings if w not in given.notes]
        assert session_only == command.warnings, name
        compared.append(name)
    # the seeds' bench experiments the virtual rig writes, each compared (not skipped)
    assert {"lcr", "spindown", "terminal", "torque", "free-spinup", "stall"} <= set(compared), compared
