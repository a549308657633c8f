"""The artefact kind runs the study of mtmc.artefact and reports its numbers unchanged."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mtmc.errors import MtmcError
from mtmc.study import load_study, loads_study

ROOT = Path(__file__).resolve().parents[2]
STUDY = ROOT / "examples" / "studies" / "wang2022.toml"


def test_artefact_study_reports_what_simulate_computes():
    from mtmc.artefact.simulation import simulate_artefact

    r = load_study(STUDY).run(trials=300, seed=4)
    ref = simulate_artefact(load_study(STUDY).study, 300, 4)
    j = ref.to_json()
    setup = {row[0]: row for row in r.tables[1].rows}
    for name, e in j["setup_errors"].items():
        assert setup[name][3] == e["estimate"]
        assert setup[name][4] == e["u"]
    # the columns name what they hold, in SI symbols: the noise-free value apart from the
    # Monte Carlo mean, µm (not um), the rotary angles in deg
    cols = r.tables[0].columns
    assert cols[:6] == (
        "b / deg",
        "c / deg",
        "r_max noise-free / µm",
        "r_max MC mean / µm",
        "r_max MC u / µm",
        "r_max GUM u / µm",
    )
    assert r.tables[1].columns[1:3] == ("injected / µm", "identified noise-free / µm")
    assert not any("um" in c.split("/")[-1] for t in r.tables for c in t.columns)
    first = r.tables[0].rows[0]
    assert first[-4:] == tuple(
        j["poses"][0]["r_avg_model_um"][k] for k in ("noise_free", "estimate", "u", "gum_u")
    )
    field = r.fields[0]
    assert field.values.shape == field.points.shape
    assert field.unit == "µm"  # the study's unit, as its tables
    assert np.linalg.norm(field.values, axis=1).mean() == pytest.approx(
        j["volumetric_mean_um"], rel=1e-9
    )


def test_a_broken_artefact_field_keeps_its_line():
    text = STUDY.read_text(encoding="utf-8")
    lines = text.split("\n")
    i = next(n for n, ln in enumerate(lines) if ln.startswith("repetitions"))
    lines[i] = 'repetitions = "three"'
    with pytest.raises(MtmcError) as info:
        loads_study("\n".join(lines), file="w.toml", folder=STUDY.parent)
    assert info.value.line == i + 1
    assert info.value.file == "w.toml"


def test_artefact_quantities_are_the_monte_carlo_values_with_the_gum_beside_them():
    from mtmc.artefact.simulation import simulate_artefact

    r = load_study(STUDY).run(trials=300, seed=4)
    ref = simulate_artefact(load_study(STUDY).study, 300, 4)
    q = {x.name: x for x in r.quantities}
    assert len(q) == 9 + 9 + 18
    # pose (b, c) = (-5°, -5°) in mtmc's sign (the paper's b = 5°) is the sixth of the plan
    i = [tuple(p.values()) for p in ref.pose_labels()].index((-5.0, -5.0))
    rm = q["r_max.b-5_c-5"]
    # the kept samples give the engine's moments again (to rounding) and the GUM its u,
    # in the study's µm: the engine's mm times 1000
    assert {x.unit for x in r.quantities} == {"µm"}
    assert rm.mc.estimate == pytest.approx(1e3 * ref.mc_mean["r_max_measured"][i], rel=1e-12)
    assert rm.mc.u == pytest.approx(1e3 * ref.mc_u["r_max_measured"][i], rel=1e-9)
    assert rm.gum.u == pytest.approx(1e3 * ref.gum_u["r_max_measured"][i], rel=1e-12)
    assert rm.gum.estimate == pytest.approx(1e3 * ref.nominal.r_max_measured[0, i], rel=1e-9)
    # the budget line of a k-variate input gives its contribution sqrt(c V cᵀ), not the
    # first component's x, u and c; the contributions add up in quadrature to the GUM u
    cmm = next(b for b in rm.budget if b.name == "cmm")
    assert cmm.components == 15
    assert cmm.estimate is cmm.u is cmm.sensitivity is None
    assert cmm.contribution > 0
    total = np.sqrt(sum(b.contribution**2 for b in rm.budget))
    assert total == pytest.approx(rm.gum.u, rel=1e-9)
    j = ref.study.names.index("dw3y")
    s = q["setup.dw3y"]
    assert s.mc.u == pytest.approx(1e3 * ref.mc_u["setup"][j], rel=1e-9)
    assert s.gum.k == pytest.approx(1.959964, rel=1e-6)  # normal: infinite dof
    lo, hi = s.mc.shortest
    samples = 1e3 * ref.samples["setup"][:, j]
    assert np.mean((samples >= lo) & (samples <= hi)) == pytest.approx(0.95, abs=0.01)
    # the histogram is a density of the samples
    h = s.histogram
    assert float(np.sum(np.diff(h.edges) * h.density)) == pytest.approx(1.0, rel=1e-12)
    assert ref.samples["r_max_measured"].shape == (300, 9)
