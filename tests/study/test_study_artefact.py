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
    from mtmc.artefact.study import loads_artefact_study, simulate

    text = STUDY.read_text(encoding="utf-8")
    r = load_study(STUDY).run(trials=300, seed=4)
    ref = simulate(loads_artefact_study(text, str(STUDY), STUDY.parent), 300, 4)
    j = ref.to_json()
    setup = {row[0]: row for row in r.tables[1].rows}
    for name, e in j["setup_errors"].items():
        assert setup[name][3] == e["estimate"]
        assert setup[name][4] == e["u"]
    first = r.tables[0].rows[0]
    assert first[-4:] == tuple(
        j["poses"][0]["r_avg_model_um"][k] for k in ("noise_free", "estimate", "u", "gum_u")
    )
    field = r.fields[0]
    assert field.values.shape == field.points.shape
    assert np.linalg.norm(field.values, axis=1).mean() * 1e3 == pytest.approx(
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
