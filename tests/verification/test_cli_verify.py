"""``mtmc verify simulate`` and ``identify``; the shipped verification studies."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from mtmc.cli.main import main
from mtmc.errors import InputError
from mtmc.study import load_study, loads_study
from mtmc.verification.compensation import loads_plain_csv
from mtmc.verification.identify import identify

ROOT = Path(__file__).resolve().parents[2]
STUDIES = ROOT / "examples" / "studies"


def test_shipped_studies_load_with_the_papers_numbers() -> None:
    s16 = load_study(STUDIES / "aguado2016.toml").study
    assert {k: v.q.shape[0] for k, v in s16.points.items()} == {
        "mesh96": 96,
        "cloud96": 96,
        "mesh5408": 5408,
    }
    assert list(s16.trackers) == ["pos1", "pos2", "pos3", "pos4"]
    assert np.allclose(s16.trackers["pos4"].position, [1100.0, -1000.0, 600.0])
    cloud, mesh = s16.points["cloud96"].q, s16.points["mesh96"].q
    assert not np.allclose(cloud, mesh)
    assert np.abs(cloud - mesh).max() <= 250.0
    k17 = load_study(STUDIES / "aguado2017.toml")
    s17 = k17.study
    lt = s17.trackers["aguado2017"]
    assert np.allclose(np.degrees(lt.euler("xyz")), [0.0339, 0.0343, 59.4652])
    assert s17.noise.azimuth == 24e-6
    assert s17.noise.u_range(1000.0) == pytest.approx(0.0048)
    assert (k17.settings.trials, k17.settings.seed) == (1000, 2017)
    assert s17.points["mesh"].q.shape == (81, 3)


def test_study_errors_name_file_line_and_field() -> None:
    text = (STUDIES / "aguado2017.toml").read_text()
    bad = text.replace("step = [50.0, 50.0, 50.0]", "step = [50.0, -50.0, 50.0]")
    with pytest.raises(InputError) as exc:
        loads_study(bad, file="s.toml")
    line = next(i for i, ln in enumerate(bad.splitlines(), 1) if ln.startswith("step"))
    assert exc.value.file == "s.toml"
    assert exc.value.line == line
    assert exc.value.field is not None
    assert exc.value.field.startswith("points.mesh")
    bad = text.replace("EXX = [54.0", "EXQ = [54.0")
    with pytest.raises(InputError, match="EXQ"):
        loads_study(bad, file="s.toml")
    bad = text.replace('noise = "aguado2017"', 'noise = "leica"')
    with pytest.raises(InputError, match="noise"):
        loads_study(bad, file="s.toml")


def test_simulate_json_contract(capsys) -> None:  # type: ignore[no-untyped-def]
    args = ["verify", "simulate", str(STUDIES / "aguado2017.toml"), "--trials", "40"]
    assert main([*args, "--seed", "3", "--json", "--no-progress"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["trials"] == 40
    assert d["seed"] == 3
    assert d["points"] == 81
    for key in ("initial_ve_um", "residual_ve_um"):
        assert set(d[key]) == {"max", "mean", "min"}
        for v in d[key].values():
            assert set(v) == {"estimate", "U", "k", "p", "u", "unit", "reported"}
            assert v["unit"] == "µm"
            assert v["u"] >= 0
    assert d["initial_ve_um"]["mean"]["estimate"] > d["residual_ve_um"]["mean"]["estimate"]
    assert set(d["coefficients"]) == set(d["gum"])
    ec0y = d["coefficients"]["EC0Y"]
    assert d["unit"] == "µm"
    assert ec0y["unit"] == "µrad"
    assert abs(ec0y["estimate"] - 40.0) < 5 * ec0y["u"]
    assert d["point_u_um"]["max"] >= d["point_u_um"]["mean"] > 0
    assert main(["verify", "simulate", str(STUDIES / "aguado2017.toml"), "--tracker", "x"]) == 2
    assert "no tracker position 'x'" in capsys.readouterr().err


def test_simulate_text_rounds_as_the_gum_says(capsys) -> None:  # type: ignore[no-untyped-def]
    # the same run as text: each statistic with its u to two significant digits and the
    # estimate to its decimal place (JCGM 100 §7.2.6), u named, not given as ±
    from mtmc.uncertainty.tolerance import round_to_uncertainty

    args = ["verify", "simulate", str(STUDIES / "aguado2017.toml"), "--trials", "40"]
    assert main([*args, "--seed", "3", "--json", "--no-progress"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert main([*args, "--seed", "3", "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert "±" not in out
    assert "U (k, p = 95 %) and u" in out
    v = d["initial_ve_um"]["max"]
    y, big_u = v["reported"]["estimate"], v["reported"]["U"]
    u = round_to_uncertainty(v["u"], v["u"])[1]
    assert f"initial max : {y}  U = {big_u} (k = {v['k']:.3f})  u = {u}" in out
    pu = d["point_u_um"]
    mx, mean = (round_to_uncertainty(pu[k], pu[k])[1] for k in ("max", "mean"))
    assert f"calibration u per point: max {mx} µm, mean {mean} µm (MC)" in out


def test_identify_from_csv_and_export(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    study = STUDIES / "aguado2017.toml"
    st = load_study(study).study
    ver = st.verification()
    x = ver.readings()
    rows = ["# commanded X Y Z (mm), tracker readings (mm)", "X,Y,Z,x_lt,y_lt,z_lt"]
    rows += [",".join(f"{v:.9f}" for v in (*q, *p)) for q, p in zip(ver.q, x, strict=True)]
    data = tmp_path / "data.csv"
    data.write_text("\n".join(rows) + "\n")
    out = tmp_path / "comp.csv"
    cmd = ["verify", "identify", str(data), "--study", str(study), "--json"]
    assert main([*cmd, "--export", "csv", "-o", str(out)]) == 0
    d = json.loads(capsys.readouterr().out)
    ref = identify(st.model, ver.q, np.round(x, 9), ver.tracker, fixed=st.fixed)
    assert d["converged"]
    assert d["residual_ve_um"]["max"] < 1e-3
    for i, n in enumerate(ref.names[:-6]):
        f = 1e6 if st.machine.error_term(n.split("[")[0]).angular else 1e3
        assert d["coefficients"][n]["estimate"] == pytest.approx(ref.estimate[0, i] * f, rel=1e-6)
    table = loads_plain_csv(out.read_text())
    xs = table.curve("EXX").positions
    truth = st.truth["EXX"](xs)
    fitted = table.curve("EXX").values
    # the identified positioning error equals the machine's up to a constant and a slope
    # (absorbed by the tracker pose and the squareness), here both zero at X = 0
    assert np.allclose(fitted - fitted[0], truth - truth[0], atol=2e-4)
    bad = tmp_path / "bad.csv"
    bad.write_text("X,Y,x_lt,y_lt,z_lt\n0,0,1,2,3\n")
    assert main(["verify", "identify", str(bad), "--study", str(study)]) == 2
    assert "missing columns Z" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("conversion", "k"), [("rectangular", 1.7320508075688772), ("typical", 2.0)]
)
def test_study_mpe_noise_is_scaled_once(conversion: str, k: float) -> None:
    # ADM ±(10 µm + 0.3 µm/m), transverse ±(15 µm + 6 µm/m), u = MPE/k, by hand in mm and rad:
    # u_L = 10e-3/k + 0.3e-6/k·L, u_α = u_β = 6e-6/k + (15e-3/k)/L
    text = (STUDIES / "aguado2017.toml").read_text()
    table = f'{{ adm = [10.0, 0.3], transverse = [15.0, 6.0], conversion = "{conversion}" }}'
    s = loads_study(text.replace('"aguado2017"\neuler', f"{table}\neuler")).study
    n = s.noise
    assert n.radial_a == pytest.approx(0.010 / k, rel=1e-15)
    assert n.radial_b == pytest.approx(0.3e-6 / k, rel=1e-15)
    assert n.azimuth == n.elevation == pytest.approx(6e-6 / k, rel=1e-15)
    assert n.transverse_a == pytest.approx(0.015 / k, rel=1e-15)
    # at L = 2 m: u_L = (10 + 0.6) µm / k, u_α = (6 + 7.5) µrad / k
    u = n.u_spherical(2000.0)
    assert u.tolist() == pytest.approx([10.6e-3 / k, 13.5e-6 / k, 13.5e-6 / k], rel=1e-14)
    assert n.source.endswith("ADM ±(10 µm + 0.3 µm/m), transverse ±(15 µm + 6 µm/m)")
    assert all(t.noise == n for t in s.trackers.values())


def _identify_rows() -> tuple[Path, list[str]]:
    study = STUDIES / "aguado2017.toml"
    ver = load_study(study).study.verification()
    rows = ["X,Y,Z,x_lt,y_lt,z_lt"]
    rows += [
        ",".join(f"{v:.9f}" for v in (*q, *p)) for q, p in zip(ver.q, ver.readings(), strict=True)
    ]
    return study, rows


@pytest.mark.parametrize(
    ("row", "where", "what"),
    [
        (
            "0,5,0,0,0,0,271,7,-842,9,-677,1",
            ":2:",
            "expected 6 cells, one per header column, got 12",
        ),
        ("1_0,0,0,271.7,-842.9,-677.1", ":2:1: field X:", "plain decimal number"),
        ("\u0661,0,0,271.7,-842.9,-677.1", ":2:1: field X:", "plain decimal number"),
        ("\uff11,0,0,271.7,-842.9,-677.1", ":2:1: field X:", "plain decimal number"),
        ("0,\u00a00,0,271.7,-842.9,-677.1", ":2:2: field Y:", "plain decimal number"),
        ("0,0,0,271.7,-842.9,-677.1,5", ":2:", "expected 6 cells, one per header column, got 7"),
        ("0,0,0,271.7,-842.9", ":2:", "expected 6 cells, one per header column, got 5"),
        ("0,0,0,271.7,-842.9,nan", ":2:6: field z_lt:", "plain decimal number"),
        ("0,0,0,271.7,-842.9,inf", ":2:6: field z_lt:", "plain decimal number"),
        ("0,0,0,271.7,-842.9,1e400", ":2:6: field z_lt:", "finite number"),
    ],
)
def test_identify_takes_plain_decimals_one_per_column(  # type: ignore[no-untyped-def]
    tmp_path: Path, capsys, row: str, where: str, what: str
) -> None:
    study, rows = _identify_rows()
    rows[1] = row
    data = tmp_path / "data.csv"
    data.write_text("\n".join(rows) + "\n", encoding="utf-8")
    assert main(["verify", "identify", str(data), "--study", str(study)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert f"{data}{where}" in err
    assert what in err


@pytest.mark.parametrize("how", ["not converged", "non-finite"])
def test_identify_refuses_a_run_that_did_not_converge(  # type: ignore[no-untyped-def]
    tmp_path: Path, capsys, monkeypatch, how: str
) -> None:
    import dataclasses

    import mtmc.verification.identify as ident

    real = ident.identify

    def broken(*args, **kwargs):  # type: ignore[no-untyped-def]
        r = real(*args, **kwargs)
        if how == "not converged":
            return dataclasses.replace(r, status=np.zeros_like(r.status))
        est = np.array(r.estimate)
        est[0, 0] = np.inf
        return dataclasses.replace(r, estimate=est)

    monkeypatch.setattr(ident, "identify", broken)
    study, rows = _identify_rows()
    data = tmp_path / "data.csv"
    data.write_text("\n".join(rows) + "\n", encoding="utf-8")
    assert main(["verify", "identify", str(data), "--study", str(study), "--json"]) == 2
    out, err = capsys.readouterr()
    assert out == ""
    assert err.count("\n") == 1
    assert err.startswith(f"mtmc: error: {data}: the identification ")
    assert "check that the readings are in mm" in err


def test_oversized_simulation_names_the_option(capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    import mtmc.uncertainty.montecarlo as mc

    monkeypatch.setattr(mc, "_memory_bytes", lambda: 2**20)
    study = STUDIES / "aguado2017.toml"
    assert main(["verify", "simulate", str(study), "--trials", "5000"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert "keep=False" not in err
    assert err.startswith("mtmc: error: keeping the samples of 5000 trials needs ")
    assert err.endswith(
        "the verification keeps the volumetric errors and coefficients of every trial: run "
        f"fewer trials (--trials N, or trials in the [run] table of {study})\n"
    )
