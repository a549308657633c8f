"""The CSV reader of positioning tests: layout, column mapping, units, and errors with lines."""

from __future__ import annotations

import numpy as np
import pytest

from mtmc.errors import InputError
from mtmc.positioning import (
    load_positioning_csv,
    loads_positioning_csv,
    parse_directions,
    parse_units,
    reading_times,
)

GOOD = """# a comment
target,run,direction,deviation,temperature
0,1,+,0.0,20.1
100,1,+,1.5,20.1
100,1,-,0.5,20.1
0,1,-,-1.0,20.1
0,2,up,0.2,20.2
100,2,up,1.7,20.2
100,2,down,0.7,20.2
0,2,down,-0.8,20.2
"""


def test_reads_the_layout_whatever_the_order():
    t = loads_positioning_csv(GOOD, "g.csv")
    assert t.targets.tolist() == [0.0, 100.0]
    assert t.runs == (1, 2)
    assert (t.unit, t.target_unit, t.m, t.n, t.rotary) == ("um", "mm", 2, 2, False)
    np.testing.assert_array_equal(t.deviations[1, :, 0], [1.5, 1.7])
    np.testing.assert_array_equal(t.deviations[0, :, 1], [-1.0, -0.8])


def test_column_mapping_semicolons_and_units():
    text = "Pos;Lauf;Richtung;Abw\n0;1;+;1\n5;1;+;2\n5;1;-;3\n0;1;-;4\n"
    text += "0;2;+;1\n5;2;+;2\n5;2;-;3\n0;2;-;4\n"
    cols = {"target": "pos", "run": "Lauf", "direction": "Richtung", "deviation": "Abw"}
    t = loads_positioning_csv(text, columns=cols, units="deg,arcsec")
    assert (t.target_unit, t.unit, t.rotary) == ("deg", "arcsec", True)
    assert t.deviations[:, 0, :].tolist() == [[1.0, 4.0], [2.0, 3.0]]


def test_units():
    assert parse_units("mm,mm") == ("mm", "mm")
    assert parse_units("arcsec") == ("deg", "arcsec")
    for bad in ("m,um", "deg,um", "mm,urad", "inch", "a,b,c"):
        with pytest.raises(InputError, match="TARGET,DEVIATION"):
            parse_units(bad)


@pytest.mark.parametrize(
    ("text", "line", "field", "match"),
    [
        (GOOD.replace("100,1,+,1.5", "100,1,+,x"), 4, "deviation", "expected a finite number"),
        (GOOD.replace("100,1,+,1.5", "100,1,+,nan"), 4, "deviation", "expected a finite number"),
        (GOOD.replace("100,1,-,0.5", "100,1,sideways,0.5"), 5, "direction", "direction"),
        (GOOD.replace("0,2,up,0.2", "0,two,up,0.2"), 7, "run", "whole run number"),
        # a run number past int64 (an OverflowError before)
        (GOOD.replace("0,2,up,0.2", "0," + "9" * 30 + ",up,0.2"), 7, "run", "at most 1000000000"),
        (GOOD.replace("0,2,up,0.2", "0,10000000001,up,0.2"), 7, "run", "at most 1000000000"),
        (GOOD.replace("0,2,up,0.2", "0,1,up,0.2"), 7, None, "second reading .* line 3"),
        (GOOD.replace("0,2,up,0.2,20.2", "0,2,up"), 7, None, "expected 5 fields"),
        (GOOD.replace("deviation", "error"), 2, "deviation", "no column 'deviation'"),
    ],
)
def test_errors_name_the_line_and_field(text, line, field, match):
    with pytest.raises(InputError, match=match) as exc:
        loads_positioning_csv(text, "t.csv")
    assert (exc.value.file, exc.value.line, exc.value.field) == ("t.csv", line, field)


def test_missing_reading_and_empty_file():
    text = "\n".join(GOOD.splitlines()[:-1])
    with pytest.raises(InputError, match="no reading at target 0 mm, run 2, direction down"):
        loads_positioning_csv(text, "t.csv")
    with pytest.raises(InputError, match="has none"):
        loads_positioning_csv("# only a comment\n", "t.csv")
    with pytest.raises(InputError, match="no column 'run'"):
        loads_positioning_csv("target\n1\n", "t.csv")
    with pytest.raises(InputError, match="unknown column 'position'"):
        loads_positioning_csv(GOOD, columns={"position": "x"})


def test_file_reading(tmp_path):
    p = tmp_path / "t.csv"
    p.write_text("\ufeff" + GOOD, encoding="utf-8")
    assert load_positioning_csv(p).m == 2
    with pytest.raises(InputError, match="cannot read") as exc:
        load_positioning_csv(tmp_path / "none.csv")
    assert exc.value.file.endswith("none.csv")


def test_reading_times_follow_the_standard_cycle():
    tau = reading_times(3, 2)
    order = np.sort(tau.ravel())
    np.testing.assert_allclose(order, np.arange(12) / 11)  # each reading once
    assert tau[0, 0, 0] == 0.0
    assert tau[2, 0, 0] < tau[2, 0, 1] < tau[0, 0, 1] < tau[0, 1, 0]


@pytest.mark.parametrize(
    ("up", "down"),
    [("Forward", "Reverse"), ("fwd", "bwd"), ("up", "down"), ("+", "−"), ("1", "-1"), ("↑", "↓")],
)
def test_the_common_direction_words_read_without_a_mapping(up, down):
    text = GOOD.replace(",+,", f",{up},").replace(",up,", f",{up},")
    text = text.replace(",-,", f",{down},").replace(",down,", f",{down},")
    t = loads_positioning_csv(text, "g.csv")
    np.testing.assert_array_equal(t.deviations, loads_positioning_csv(GOOD).deviations)


def test_a_mapping_names_other_words():
    text = GOOD.replace(",+,", ",Hin,").replace(",up,", ",Hin,")
    text = text.replace(",-,", ",Rück,").replace(",down,", ",Rück,")
    with pytest.raises(InputError, match="expected a direction, got 'Hin'") as exc:
        loads_positioning_csv(text, "g.csv")
    assert (exc.value.line, exc.value.field) == (3, "direction")
    good = loads_positioning_csv(GOOD).deviations
    for mapping in ("Hin=up,Rück=down", {"hin": "up", "RÜCK": "-"}):
        t = loads_positioning_csv(text, "g.csv", directions=mapping)
        np.testing.assert_array_equal(t.deviations, good)
    # a word of the defaults can be turned round
    flipped = loads_positioning_csv(GOOD, directions="+=down,-=up,up=down,down=up")
    np.testing.assert_array_equal(flipped.deviations, good[:, :, ::-1])
    for bad in ("Hin", "Hin=sideways", "=up"):
        with pytest.raises(InputError, match="WORD=up") as exc:
            parse_directions(bad)
        assert exc.value.field == "directions"


def test_completeness_is_checked_from_the_rows_in_bounded_memory():
    # 25 000 rows, each a new target and a new run: the product of the labels would be an
    # array of 1.25·10⁹ readings (9.3 GiB); the check needs memory of the order of the rows
    # (at 100 000 rows, 32 MB against 149 GiB; tracemalloc made that 11 s of the suite)
    import tracemalloc

    rows = ["target,run,direction,deviation"]
    rows += [f"{k},{k + 1},+,0.5" for k in range(25_000)]
    text = "\n".join(rows) + "\n"
    tracemalloc.start()
    try:
        with pytest.raises(InputError, match="no reading at target 0 mm, run 1, direction down"):
            loads_positioning_csv(text, "big.csv")
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    # the lines of the text and an array of each column (8.2 MB measured); the product of
    # the labels would be 10 GB
    assert peak < 50e6
    # a complete test of 200 targets × 50 runs (20 000 rows) reads, laid out by label
    rng = np.random.default_rng(5)
    x = rng.standard_normal((200, 50, 2))
    rows = ["target,run,direction,deviation"]
    order = rng.permutation(x.size)
    for flat in order:
        i, j, d = np.unravel_index(flat, x.shape)
        rows.append(f"{i},{j + 1},{'+-'[d]},{float(x[i, j, d])!r}")
    t = loads_positioning_csv("\n".join(rows), "ok.csv")
    np.testing.assert_array_equal(t.deviations, x)  # bit for bit: repr round-trips
