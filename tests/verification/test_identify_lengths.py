"""``mtmc verify identify`` from lengths per station (multilateration) and from coordinates."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from mtmc.cli.main import main
from mtmc.errors import InputError
from mtmc.study import load_study
from mtmc.verification.datafile import loads_identification_csv, measured_points

STUDY = Path(__file__).resolve().parents[2] / "examples" / "studies" / "aguado2016.toml"


def _write(path: Path, head: list[str], q: np.ndarray, vals: np.ndarray) -> None:
    rows = [",".join(head)] + [
        ",".join(f"{v:.17g}" for v in (*a, *b)) for a, b in zip(q, vals, strict=True)
    ]
    path.write_text("# noise-free, simulated\n" + "\n".join(rows) + "\n")


def test_lengths_give_the_same_identification_as_coordinates(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    st = load_study(STUDY).study
    ver = st.verification("mesh96", "pos4")
    p = ver.true_positions()  # the simulated machine, base frame
    q = ver.q
    names = ("pos1", "pos2", "pos3")
    C = np.array([st.trackers[n].position for n in names])
    L = np.linalg.norm(p[:, None, :] - C[None], axis=-1)  # (N, S)
    _write(tmp_path / "lengths.csv", ["X", "Y", "Z", *(f"L_{n}" for n in names)], q, L)
    _write(tmp_path / "xyz.csv", ["X", "Y", "Z", "x_lt", "y_lt", "z_lt"], q, ver.readings())
    # multilateration recovers the points exactly (noise-free)
    d = loads_identification_csv(
        (tmp_path / "lengths.csv").read_text(), ("X", "Y", "Z"), st.trackers
    )
    assert d.kind == "lengths"
    assert d.stations == names
    pts, lt = measured_points(d, st.machine, st.trackers, ver.tracker)
    assert np.abs(pts - p).max() < 1e-9
    assert np.allclose(lt.rotation, np.eye(3))
    assert np.allclose(lt.position, 0.0)
    out = {}
    for kind in ("lengths", "xyz"):
        args = ["verify", "identify", str(tmp_path / f"{kind}.csv"), "--study", str(STUDY)]
        assert main([*args, "--tracker", "pos4", "--json"]) == 0
        out[kind] = json.loads(capsys.readouterr().out)
    a, b = out["lengths"], out["xyz"]
    assert a["data"] == "lengths"
    assert a["stations"] == list(names)
    assert b["data"] == "coordinates"
    assert a["converged"]
    assert b["converged"]
    # the residual is frame-invariant: the same optimum, the pose absorbing the frames
    for name, c in b["coefficients"].items():
        if not name.startswith("LT."):
            assert a["coefficients"][name]["estimate"] == pytest.approx(c["estimate"], rel=1e-6)
            assert a["coefficients"][name]["u"] == pytest.approx(c["u"], rel=1e-6)
    for k in ("max", "mean", "min"):
        assert a["residual_ve_um"][k] == pytest.approx(b["residual_ve_um"][k], rel=1e-6, abs=1e-9)


def test_bad_length_columns_are_named() -> None:
    st = load_study(STUDY).study
    with pytest.raises(InputError, match="L_nowhere"):
        loads_identification_csv(
            "X,Y,Z,L_pos1,L_nowhere,L_pos2\n0,0,0,1,1,1\n", ("X", "Y", "Z"), st.trackers, "d.csv"
        )
    with pytest.raises(InputError, match="three or more stations"):
        loads_identification_csv(
            "X,Y,Z,L_pos1,L_pos2\n0,0,0,1,1\n", ("X", "Y", "Z"), st.trackers, "d.csv"
        )
    with pytest.raises(InputError, match=r"d.csv:2:3: field Z: expected a plain decimal number"):
        loads_identification_csv(
            "X,Y,Z,x_lt,y_lt,z_lt\n0,0,zero,1,1,1\n", ("X", "Y", "Z"), {}, "d.csv"
        )


def test_self_calibrated_stations_give_the_coordinates_identification(
    tmp_path: Path,
    capsys,  # type: ignore[no-untyped-def]
) -> None:
    st = load_study(STUDY).study
    ver = st.verification("mesh96", "pos4")
    p = ver.true_positions()
    q = ver.q
    names = ("pos1", "pos2", "pos3", "pos4")
    nominal = np.array([st.trackers[n].position for n in names])
    # the stations stand up to 2 mm away from where the study says
    moved = nominal + np.array(
        [[1.5, -0.8, 0.3], [-1.2, 2.0, -0.6], [0.7, 1.1, 1.9], [-2.0, -0.4, 0.9]]
    )
    L = np.linalg.norm(p[:, None, :] - moved[None], axis=-1)
    _write(tmp_path / "lengths.csv", ["X", "Y", "Z", *(f"L_{n}" for n in names)], q, L)
    _write(tmp_path / "xyz.csv", ["X", "Y", "Z", "x_lt", "y_lt", "z_lt"], q, ver.readings())
    d = loads_identification_csv(
        (tmp_path / "lengths.csv").read_text(), ("X", "Y", "Z"), st.trackers
    )
    # self-calibrated: the points in the datum frame of the moved stations, exactly;
    # the frame returned is the datum of the nominal stations, off by about 2 mm
    pts, frame = measured_points(d, st.machine, st.trackers, ver.tracker, self_calibrated=True)
    R = np.linalg.qr((moved[1:3] - moved[0]).T)[0]
    R = R * np.sign(np.diag(R.T @ (moved[1:3] - moved[0]).T))  # columns: datum x, y
    R = np.column_stack([R, np.cross(R[:, 0], R[:, 1])])
    np.testing.assert_allclose(pts, (p - moved[0]) @ R, atol=1e-8)
    assert 0.5 < np.linalg.norm(frame.position - moved[0]) < 3.0
    # from the nominal stations, the points are off by about the stations' errors
    off, _ = measured_points(d, st.machine, st.trackers, ver.tracker)
    assert np.abs(off - p).max() > 0.1
    out = {}
    for kind, extra in (("self", ["--self-calibrate"]), ("plain", []), ("xyz", [])):
        csv_name = "xyz.csv" if kind == "xyz" else "lengths.csv"
        args = ["verify", "identify", str(tmp_path / csv_name), "--study", str(STUDY)]
        assert main([*args, "--tracker", "pos4", "--json", *extra]) == 0
        out[kind] = json.loads(capsys.readouterr().out)
    a, plain, b = out["self"], out["plain"], out["xyz"]
    assert a["self_calibrated"]
    assert not plain["self_calibrated"]
    assert a["converged"]
    worst_plain = 0.0
    for name, c in b["coefficients"].items():
        if not name.startswith("LT."):
            assert a["coefficients"][name]["estimate"] == pytest.approx(
                c["estimate"], rel=1e-6, abs=1e-9 * max(1.0, abs(c["estimate"]))
            )
            assert a["coefficients"][name]["u"] == pytest.approx(c["u"], rel=1e-6)
            worst_plain = max(
                worst_plain, abs(plain["coefficients"][name]["estimate"] - c["estimate"])
            )
    for k in ("max", "mean", "min"):
        assert a["residual_ve_um"][k] == pytest.approx(b["residual_ve_um"][k], rel=1e-6, abs=1e-9)
    # the stations' errors bend the lengths' geometry: the plain route leaves a residual
    assert plain["residual_ve_um"]["max"] > 10 * max(b["residual_ve_um"]["max"], 1e-3)
    args = ["verify", "identify", str(tmp_path / "lengths.csv"), "--study", str(STUDY)]
    assert main([*args, "--tracker", "pos4", "--self-calibrate"]) == 0
    assert "lengths of 4 stations, positions self-calibrated" in capsys.readouterr().out
    assert worst_plain > 0


def test_self_calibration_is_refused_for_coordinates_and_three_stations(tmp_path: Path) -> None:
    st = load_study(STUDY).study
    ver = st.verification("mesh96", "pos4")
    xyz = loads_identification_csv(
        "X,Y,Z,x_lt,y_lt,z_lt\n0,0,0,1,1,1\n", ("X", "Y", "Z"), st.trackers, "d.csv"
    )
    with pytest.raises(InputError, match="lengths per station"):
        measured_points(xyz, st.machine, st.trackers, ver.tracker, self_calibrated=True)
    p = ver.true_positions()
    names = ("pos1", "pos2", "pos3")
    C = np.array([st.trackers[n].position for n in names])
    L = np.linalg.norm(p[:, None, :] - C[None], axis=-1)
    _write(tmp_path / "l3.csv", ["X", "Y", "Z", *(f"L_{n}" for n in names)], ver.q, L)
    d = loads_identification_csv((tmp_path / "l3.csv").read_text(), ("X", "Y", "Z"), st.trackers)
    with pytest.raises(InputError, match="at least four stations"):
        measured_points(d, st.machine, st.trackers, ver.tracker, self_calibrated=True)
