"""``motorlab analyze``: tables, JSON, --each, --plot, and one-line errors for bad input."""

from __future__ import annotations

import json

import numpy as np
import pytest

from motorlab import cli
from motorlab.io import write_csv
from motorlab.units import STANDARD_GRAVITY

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def run(capsys, *argv: str) -> tuple[int, str, str]:
    code = cli.main(["analyze", *argv])
    out, err = capsys.readouterr()
    return code, out, err


def torque_file(path, *, k: float = 0.105, arm: float = 0.1, seed: int = 0, grams: bool = True) -> None:
    rng = np.random.default_rng(seed)
    current = np.arange(0.5, 4.01, 0.5)
    mass = (k * current + rng.uniform(-0.002, 0.002, current.size)) / (STANDARD_GRAVITY * arm)
    column = {"mass_g": np.round(1000 * mass, 0)} if grams else {"mass_kg": np.round(mass, 3)}
    write_csv(path, {"current_A": current, **column}, metadata={"arm_m": arm})


def lcr_file(path) -> None:
    write_csv(
        path,
        {
            "L_uH": [697.2, 643, 645.2, 731.4, 732.8, 646.4, 695.9, 645.6, 656.4, 641.2],
            "Q": [1.03, 2, 1.38, 1.94, 2.17, 1.92, 1.77, 1.79, 1.7, 2.08],
            "DCR_ohm": [3.65, 1.46, 2.35, 1.75, 1.49, 1.57, 1.83, 1.69, 1.81, 1.38],
        },
        metadata={"frequency_Hz": 1000},
    )


def test_json_object_in_si(tmp_path, capsys):
    path = tmp_path / "torque.csv"
    torque_file(path)
    code, out, err = run(capsys, "torque", str(path), "--json")
    assert code == 0, err
    doc = json.loads(out)
    assert doc["experiment"] == "torque"
    assert doc["parameters"]["K"]["unit"] == "V*s/rad"
    assert doc["parameters"]["K"]["value"] == pytest.approx(0.105, rel=0.01)
    assert doc["parameters"]["K"]["stderr"] > 0
    assert set(doc["fit"]) >= {"rmse", "r2"}
    assert isinstance(doc["warnings"], list)


def test_options_take_quantities(tmp_path, capsys):
    path = tmp_path / "torque.csv"
    torque_file(path, arm=0.1)
    _, out_m, _ = run(capsys, "torque", str(path), "--json", "--arm", "0.2")
    _, out_cm, _ = run(capsys, "torque", str(path), "--json", "--arm", "20 cm")
    k_m = json.loads(out_m)["parameters"]["K"]["value"]
    assert k_m == pytest.approx(json.loads(out_cm)["parameters"]["K"]["value"], rel=1e-12)
    assert k_m == pytest.approx(0.21, rel=0.01)


def test_each_gives_a_list_and_pooled_gives_one(tmp_path, capsys):
    paths = []
    for unit, k in zip("ABC", (0.100, 0.105, 0.110), strict=True):
        paths.append(tmp_path / f"unit{unit}.csv")
        torque_file(paths[-1], k=k, grams=unit != "B")
    code, out, _ = run(capsys, "torque", *map(str, paths), "--json", "--each")
    assert code == 0
    docs = json.loads(out)
    assert [d["parameters"]["K"]["value"] for d in docs] == pytest.approx([0.100, 0.105, 0.110], rel=0.01)
    assert [d["sources"] for d in docs] == [[str(p)] for p in paths]
    code, out, _ = run(capsys, "torque", *map(str, paths), "--json")
    assert json.loads(out)["fit"]["n_points"] == 24


def test_human_table_and_plot(tmp_path, capsys):
    path = tmp_path / "lcr.csv"
    lcr_file(path)
    png = tmp_path / "lcr.png"
    code, out, err = run(capsys, "lcr", str(path), "--plot", str(png))
    assert code == 0, err
    for text in ("R_dc", "±", "Ω"):
        assert text in out
    assert "use R_dc" in out  # the warning saying which R to trust
    assert "\x1b[" not in out  # no colour codes when not a terminal
    assert png.read_bytes()[:8] == PNG_MAGIC


def test_each_with_plot_writes_one_figure_per_file(tmp_path, capsys):
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    torque_file(a)
    torque_file(b, seed=1)
    code, out, _ = run(capsys, "torque", str(a), str(b), "--each", "--plot", str(tmp_path / "k.png"))
    assert code == 0
    assert (tmp_path / "k-a.png").exists()
    assert (tmp_path / "k-b.png").exists()
    assert out.count("torque:") == 2


def test_amplifier_nominal(tmp_path, capsys):
    path = tmp_path / "amp.csv"
    v = np.arange(0.5, 2.6, 0.5)
    write_csv(path, {"command_V": v, "current_A": np.round(1.5 * v, 3)})
    code, out, _ = run(capsys, "amplifier", str(path), "--nominal", "2 A/V", "--json")
    assert code == 0
    doc = json.loads(out)
    assert doc["parameters"]["Ka"]["value"] == pytest.approx(1.5)
    assert any("nominal" in w for w in doc["warnings"])


BAD_FILES = {
    "empty.csv": b"",
    "binary.csv": bytes(range(256)) * 4,
    "text.csv": b"current_A,mass_g\n1.0,abc\n2.0,300\n",
    "nan.csv": b"current_A,mass_g\n1.0,100\nnan,200\n3.0,300\n",
    "short-row.csv": b"current_A,mass_g\n1.0,100\n2.0\n3.0,300\n",
    "one-row.csv": b"# arm_m: 0.1\ncurrent_A,mass_g\n1.0,100\n",
    "no-mass.csv": b"# arm_m: 0.1\ncurrent_A,command_V\n1.0,0.5\n2.0,1.0\n3.0,1.5\n",
}


@pytest.mark.parametrize("name", [*BAD_FILES, "missing.csv"])
def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys, name):
    path = tmp_path / name
    if name in BAD_FILES:
        path.write_bytes(BAD_FILES[name])
    code, out, err = run(capsys, "torque", str(path), "--arm", "0.1")
    assert code == 2
    assert out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert "Traceback" not in err
    assert name in lines[0]


def test_bad_options_are_one_line_and_exit_2(tmp_path, capsys):
    path = tmp_path / "torque.csv"
    torque_file(path)
    with pytest.raises(SystemExit) as exc:
        cli.main(["analyze", "torque", str(path), "--arm", "3 kg"])
    assert exc.value.code == 2
    with pytest.raises(SystemExit):
        cli.main(["analyze", "pulse", str(path)])  # --Ka and --Km are required
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 2
    code, _, err = run(capsys, "torque", str(path), "--plot", str(tmp_path / "fig.bmp"))
    assert code == 2
    assert len(err.strip().splitlines()) == 1
