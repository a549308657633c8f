"""Hostile input: every file mtmc reads, mutated, ends in a result or in one line of error.

The budget is small and fixed (``MTMC_FUZZ_EXAMPLES``, default 25 cases, derandomised) so
that the suite stays fast; ``make fuzz`` runs the same property with a larger budget and a
random campaign with counts (``tests/fuzz/mtmc_fuzz.py``).
"""

from __future__ import annotations

import os
import re
import shutil
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from mtmc_fuzz import (
    CSV_OPS,
    NUMBER_OPS,
    TOML_OPS,
    Target,
    make_tree,
    mutate,
    mutate_csv,
    mutate_numbers,
    mutate_toml,
    ops_for,
    run_case,
    targets,
)

from mtmc.cli.main import main
from mtmc.document import MAX_DEPTH, loads_toml
from mtmc.errors import DegenerateGeometryError, InputError, ParseError
from mtmc.instruments.multilateration import self_calibrate, trilaterate
from mtmc.io import decode_utf8

EXAMPLES = int(os.environ.get("MTMC_FUZZ_EXAMPLES", "25"))
TARGETS = targets()


@pytest.fixture(scope="module")
def tree(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("fuzz")
    make_tree(root)
    return root


@st.composite
def cases(draw: st.DrawFn) -> tuple[Target, list[tuple[str, int]]]:
    target = draw(st.sampled_from(TARGETS))
    ops = draw(
        st.lists(
            st.tuples(st.sampled_from(ops_for(target)), st.integers(0, 2**32 - 1)),
            min_size=1,
            max_size=2,
        )
    )
    return target, ops


@settings(
    max_examples=EXAMPLES,
    deadline=None,
    derandomize=EXAMPLES <= 100,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(case=cases())
def test_mutated_files_give_a_result_or_one_line(
    tree: Path, case: tuple[Target, list[tuple[str, int]]]
) -> None:
    target, ops = case
    data = mutate(target, (tree / target.path).read_bytes(), ops)
    outcome = run_case(target, data, tree, timeout=120.0)
    assert outcome.kind in ("ok", "error"), (target.name, ops, outcome)


def test_the_unmutated_files_run(tree: Path) -> None:
    for target in TARGETS:
        if target.cost == 1 and target.name.startswith(("graph:", "points", "comp:")):
            outcome = run_case(target, (tree / target.path).read_bytes(), tree)
            assert outcome.kind == "ok", (target.name, outcome)


@pytest.mark.parametrize("name", ["graph-sweep", "verify-simulate", "verify-plan"])
def test_the_sweep_simulate_and_plan_targets_run(tree: Path, name: str) -> None:
    target = next(t for t in TARGETS if t.name == name)
    outcome = run_case(target, (tree / target.path).read_bytes(), tree)
    assert outcome.kind == "ok", outcome


def test_every_mutation_changes_a_file() -> None:
    toml = b'a = 1\nb = [1.5, 2]\n[[p]]\nname = "x"\nv = 3\n'
    for op in TOML_OPS:
        assert any(mutate_toml(toml, op, s) != toml for s in range(8)), op
    csv = b"x,y,z\n1.5,2,3\n4,5.25,6\n7,8,9\n"
    for op in CSV_OPS:
        assert any(mutate_csv(csv, op, s) != csv for s in range(8)), op


@pytest.mark.parametrize(
    "text",
    ["a = " + "[" * 400 + "]" * 400, "a = " + "{a = " * 40 + "1" + "}" * 40, "a = " + "[" * 10**5],
)
def test_deep_nesting_is_one_parse_error(text: str) -> None:
    with pytest.raises(ParseError, match=f"nested too deep; expected at most {MAX_DEPTH}"):
        loads_toml(text, "s.toml")


def test_nesting_up_to_the_limit_is_read() -> None:
    v = loads_toml("a = " + "[" * MAX_DEPTH + "]" * MAX_DEPTH, "s.toml").data["a"]
    for _ in range(MAX_DEPTH - 1):
        v = v[0]
    assert v == []


def test_bom_accepted_and_utf16_named() -> None:
    assert decode_utf8(b"\xef\xbb\xbfa = 1\n", "f.toml") == "a = 1\n"
    with pytest.raises(ParseError, match=r"f.toml:1:1: UTF-16 text"):
        decode_utf8("a = 1".encode("utf-16"), "f.toml")


def test_repeated_and_too_many_names_are_refused() -> None:
    top = loads_toml('o = ["a", "b", "a"]\nq = ["x", "y"]', "s.toml")
    with pytest.raises(InputError, match=r"s.toml:1: field o: 'a' is listed twice"):
        top.texts("o")
    with pytest.raises(InputError, match="expected at most 1 entries, got 2"):
        top.texts("q", max_items=1)
    assert top.texts("q") == ("x", "y")


def test_integer_maximum() -> None:
    top = loads_toml("[run]\ntrials = 10000000000000000000000000000000", "s.toml")
    run = top.table("run")
    assert run is not None
    with pytest.raises(InputError, match=r"s.toml:2: field run.trials: expected an integer <="):
        run.integer("trials", maximum=10**9)


@pytest.mark.parametrize(
    ("stations", "what"),
    [
        ([[0, 0, 0], [1000, 0, 0], [2000, 0, 0], [3000, 0, 0]], "one line"),
        ([[0, 0, 0], [1000, 0, 0], [0, 1000, 0], [1000, 1000, 0]], "one plane"),
    ],
)
def test_degenerate_stations(stations: list[list[float]], what: str) -> None:
    c = np.array(stations, dtype=float)
    p = np.random.default_rng(1).uniform(0, 500, (8, 3))
    d = np.linalg.norm(p[None] - c[:, None], axis=-1)
    with pytest.raises(DegenerateGeometryError, match=what):
        trilaterate(c, d)
    with pytest.raises(DegenerateGeometryError, match=what):
        self_calibrate(d, c)


def test_identification_numbers_out_of_range(
    tree: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    f = tree / "data" / "huge.csv"
    f.write_text("X,Y,Z,x_lt,y_lt,z_lt\n0,0,0,1,2,3\n0,0,0,1e308,2,3\n")
    study = tree / "studies" / "aguado2017.toml"
    assert main(["verify", "identify", str(f), "--study", str(study)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert "huge.csv:3:4: field x_lt: expected a finite number" in err


# hostile numbers: pathological distribution parameters, copula dof, numbers in odd scripts
_CHEAP = [t for t in TARGETS if t.cost == 1]


@settings(
    max_examples=EXAMPLES,
    deadline=None,
    derandomize=EXAMPLES <= 100,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(
    target=st.sampled_from(_CHEAP),
    op=st.sampled_from(NUMBER_OPS),
    seed=st.integers(0, 2**32 - 1),
)
def test_hostile_numbers_give_a_result_or_one_line(
    tree: Path, target: Target, op: str, seed: int
) -> None:
    if op not in ops_for(target):
        op = "odd_digits"
    data = mutate(target, (tree / target.path).read_bytes(), [(op, seed)])
    outcome = run_case(target, data, tree, timeout=120.0)
    assert outcome.kind in ("ok", "error"), (target.name, op, seed, outcome)


def test_every_number_op_changes_a_study() -> None:
    study = b'model = "a + b"\n[inputs]\na = "normal(0, 1)"\nb = "uniform(-1, 1)"\n'
    for op in NUMBER_OPS:
        assert any(mutate_numbers(study, op, s) != study for s in range(8)), op
    with_t = mutate_numbers(study, "copula_dof", 1).decode()
    assert '[correlation]\npairs = [["a", "b", 0.5]]\ncopula = {kind = "t", dof = ' in with_t


def test_numbers_the_new_strategies_broke_are_refused_with_their_place() -> None:
    # a 401-digit TOML integer (OverflowError in check_number)
    top = loads_toml("[run]\nx = 1" + "0" * 400, "s.toml")
    with pytest.raises(InputError, match=r"s.toml:2: field run.x: expected a finite number"):
        top.table("run").number("x")
    # 1e400 in the assertion database (OverflowError: float infinity to integer)
    from mtmc.graph.assertions import loads_assertions

    with pytest.raises(ParseError) as info:
        loads_assertions("p(1, 1e400, 0).\n", file="g.pl")
    assert (info.value.file, info.value.line) == ("g.pl", 1)
    assert "expected a finite number at most 1.8e+308 in size, got '1e400'" in str(info.value)


@pytest.mark.parametrize(
    ("study", "old", "new", "field"),
    [
        # make fuzz at 2000 cases: an integer past the largest float in an array of numbers
        # (OverflowError: int too large to convert to float, in three readers of [x, y, z])
        ("circle_b_axis.toml", "ball = [150.0,", "ball = [1" + "0" * 400 + ",", "rotary.ball"),
        (
            "wang2022.toml",
            "position = [0.0,",
            "position = [1" + "0" * 400 + ",",
            "artefact.position",
        ),
    ],
)
def test_a_huge_integer_in_an_array_of_numbers_is_refused_with_its_place(
    study: str, old: str, new: str, field: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text = (Path(__file__).resolve().parents[2] / "examples" / "studies" / study).read_text()
    assert old in text
    path = tmp_path / study
    path.write_text(text.replace(old, new, 1), encoding="utf-8")
    assert main(["run", str(path), "-n", "20", "-q"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    assert f"field {field}: expected" in err, err
    assert "each at most 1e+06 in size" in err, err


def test_a_huge_integer_in_an_artefact_file_is_refused_with_its_place(tmp_path: Path) -> None:
    from mtmc.artefact.artefact import load_artefact

    shipped = Path(__file__).resolve().parents[2] / "examples" / "artefacts"
    text = (shipped / "wang2022_five_ball.toml").read_text(encoding="utf-8")
    text, n = re.subn(r"centre = \[[^,\]]+,", "centre = [1" + "0" * 400 + ",", text, count=1)
    assert n == 1
    path = tmp_path / "five.toml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(InputError, match=r"field ball\[0\]\.centre: expected three finite"):
        load_artefact(path)


@pytest.mark.parametrize(
    ("study", "old", "field"),
    [
        # 10**300 trials of the Sobol budget: a multiple of its seed block, and no upper
        # limit, where [run] trials has one (MemoryError, or the machine's memory spent)
        ("mass_calibration.toml", "trials = 131072", "sensitivity.trials"),
        ("bcs_origin.toml", "trials = 1000 ", "sweep.trials"),
    ],
)
def test_trials_past_the_limit_are_refused_in_every_table(
    study: str, old: str, field: str, tmp_path: Path
) -> None:
    from mtmc.study import load_study

    examples = Path(__file__).resolve().parents[2] / "examples"
    text = (examples / "studies" / study).read_text(encoding="utf-8")
    assert old in text
    text = text.replace(old, "trials = 1" + "0" * 300 + " ", 1)
    shutil.copytree(examples / "graphs", tmp_path / "graphs")
    (tmp_path / "studies").mkdir()
    path = tmp_path / "studies" / study
    path.write_text(text, encoding="utf-8")
    with pytest.raises(InputError, match=rf"field {field}: expected an integer <= 1000000000"):
        load_study(path)


@pytest.mark.parametrize(
    ("study", "old", "new", "field"),
    [
        # a 401-digit integer where the study reads an array of arrays (OverflowError: int
        # too large to convert to float, in the correlation's and the workspace's readers)
        ("gauge_blocks_correlated.toml", '"e2", 0.9]', '"e2", 1' + "0" * 400 + "]", "pairs[0]"),
        ("aguado2016.toml", "offsets = [[0.0,", "offsets = [[1" + "0" * 400 + ",", "offsets"),
    ],
)
def test_a_huge_integer_in_an_array_of_arrays_is_refused_with_its_place(
    study: str, old: str, new: str, field: str
) -> None:
    from mtmc.study import loads_study

    studies = Path(__file__).resolve().parents[2] / "examples" / "studies"
    text = (studies / study).read_text(encoding="utf-8")
    assert old in text
    text = text.replace(old, new, 1)
    with pytest.raises(InputError) as info:
        loads_study(text, file=study, folder=studies)
    err = info.value
    assert (err.file, err.field.split(".", 1)[-1]) == (study, field)
    assert text.splitlines()[err.line - 1].lstrip().startswith(field.split("[")[0])
