"""Files that parse but are wrong: refused before anything runs, one line naming the field."""

from __future__ import annotations

from pathlib import Path

import pytest

from mtmc.errors import InputError
from mtmc.study.spec import loads_study

ROOT = Path(__file__).resolve().parents[2]
STUDIES = ROOT / "examples" / "studies"


@pytest.mark.parametrize(
    ("old", "new", "field"),
    [
        ("[nc]\n", "[nc]\nbogus_key = 1\n", "nc.bogus_key"),
        ("feed = 2630.0", "feed = -5.0", "nc.feed"),
        ('format = ["iso", "heidenhain"]', 'format = ["bogus"]', "nc.format"),
        ('path = "serpentine"', 'path = "zigzag"', "workspace.path"),
        ("[workspace]\n", "[workspace]\nbogus = 2\n", "workspace.bogus"),
    ],
)
def test_verification_study_validates_its_plan_tables(old, new, field):
    text = (STUDIES / "aguado2016.toml").read_text(encoding="utf-8")
    assert text.count(old) == 1
    with pytest.raises(InputError) as info:
        loads_study(text.replace(old, new), file="v.toml", folder=STUDIES)
    assert f"field {field}" in str(info.value)
    assert str(info.value).startswith("v.toml:")


def test_report_of_a_result_lacking_monte_carlo_is_one_error(tmp_path):
    import json

    from mtmc.cli.main import main
    from mtmc.study import load_study, write_result

    out = tmp_path / "out"
    write_result(load_study(STUDIES / "mass_calibration.toml").run(trials=200, seed=1), out)
    doc = json.loads((out / "result.json").read_text())
    del doc["quantities"][0]["monte_carlo"]
    (out / "result.json").write_text(json.dumps(doc))
    from mtmc.report import render

    with pytest.raises(InputError, match="no 'monte_carlo' where a result needs one"):
        render(out)
    assert main(["report", str(out)]) == 2
