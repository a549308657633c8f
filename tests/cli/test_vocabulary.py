"""One vocabulary across the commands of ``mtmc`` (``docs/cli.md``), and the seed printed.

The commands are read from the Typer app itself, so a command or an option added later is
checked too: every command's ``--help`` lists its options; a short form means one long
option everywhere; a long option has one short form and one type everywhere; every command
that runs a Monte Carlo (it has ``--trials``) has ``-s/--seed`` and ``--json`` and prints
the seed it used, in text and in JSON, also when it was drawn from fresh entropy.
"""

from __future__ import annotations

import json
import re
import typing
from collections import defaultdict
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
import typer

from mtmc import demo
from mtmc.cli.main import app, main

ROOT = Path(__file__).resolve().parents[2]
STUDIES = ROOT / "examples" / "studies"
GRAPHS = ROOT / "examples" / "graphs"
SEED = 4242


def _commands() -> Iterator[tuple[str, Any]]:
    """Every leaf command of ``mtmc`` as (its path, e.g. ``"graph run"``, the click command)."""

    def walk(cmd: Any, path: tuple[str, ...]) -> Iterator[tuple[str, Any]]:
        subs = getattr(cmd, "commands", None)
        if subs is None:
            yield " ".join(path), cmd
            return
        for name, sub in subs.items():
            yield from walk(sub, (*path, name))

    yield from walk(typer.main.get_command(app), ())


COMMANDS = dict(_commands())


def _options(cmd: Any) -> list[Any]:
    return [p for p in cmd.params if p.param_type_name == "option"]


def _longs(opt: Any) -> tuple[str, ...]:
    """The long names of an option, its own first (``--progress``, ``--no-progress``)."""
    return tuple(o for o in (*opt.opts, *opt.secondary_opts) if o.startswith("--"))


def _shorts(opt: Any) -> tuple[str, ...]:
    return tuple(sorted(o for o in opt.opts if not o.startswith("--")))


def _value_type(opt: Any) -> str:
    """What the option takes: ``flag``, or the type of its value (``int``, ``Path``, ...)."""
    if opt.is_flag:
        return "flag"
    click_type = getattr(opt, "type", None)  # click's own options
    if click_type is not None:
        return str(getattr(click_type, "name", click_type))
    hint = opt.type_descriptor.annotation  # Typer's options: the annotation of the parameter
    args = [a for a in typing.get_args(hint) if a is not type(None)]
    if typing.get_origin(hint) in (list, tuple) or (args and len(args) == 1):
        hint = args[0]
    return getattr(hint, "__name__", str(hint))


def _monte_carlo_commands() -> list[str]:
    """The commands that run a Monte Carlo: those with ``--trials``."""
    return [
        path
        for path, cmd in COMMANDS.items()
        if any("--trials" in _longs(o) for o in _options(cmd))
    ]


def test_a_short_form_means_one_long_option_everywhere(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    assert {"propagate", "run", "graph run", "graph sweep", "verify simulate"} <= set(COMMANDS)
    monkeypatch.setenv("COLUMNS", "200")
    meaning: dict[str, dict[str, list[str]]] = defaultdict(lambda: defaultdict(list))
    for path, cmd in COMMANDS.items():
        assert main([*path.split(), "--help"]) == 0, path
        text = capsys.readouterr().out
        for opt in _options(cmd):
            for name in (*_longs(opt), *_shorts(opt)):  # the --help lists each name
                assert re.search(rf"(?<![\w-]){re.escape(name)}(?![\w-])", text), (path, name)
            for short in _shorts(opt):
                meaning[short][_longs(opt)[0]].append(path)
    clashes = {s: dict(longs) for s, longs in meaning.items() if len(longs) > 1}
    assert not clashes, f"a short form with several meanings (short: long: commands): {clashes}"


def test_a_long_option_has_one_short_form_and_one_type_everywhere() -> None:
    seen: dict[str, dict[tuple[Any, ...], list[str]]] = defaultdict(lambda: defaultdict(list))
    for path, cmd in COMMANDS.items():
        for opt in _options(cmd):
            longs = _longs(opt)
            form = (longs, _shorts(opt), _value_type(opt), bool(opt.multiple))
            for name in longs:
                seen[name][form].append(path)
    differ = {name: dict(forms) for name, forms in seen.items() if len(forms) > 1}
    assert not differ, f"one long option spelled or typed in several ways: {differ}"


def test_the_coverage_probability_has_one_spelling() -> None:
    for path, cmd in COMMANDS.items():
        for opt in _options(cmd):
            if "coverage probability" in (opt.help or "").lower():
                got = (_longs(opt), _shorts(opt), _value_type(opt))
                assert got == (("--coverage-probability",), ("-p",), "float"), (path, got)


@pytest.mark.parametrize("path", _monte_carlo_commands())
def test_a_monte_carlo_command_has_seed_and_json(path: str) -> None:
    forms = {_longs(o)[0]: (_shorts(o), _value_type(o)) for o in _options(COMMANDS[path])}
    assert forms.get("--seed") == (("-s",), "int"), path
    assert forms.get("--json") == ((), "flag"), path


def _propagate(_tmp: Path) -> list[str]:
    return ["propagate", "a * b", "-i", "a=normal(2, 0.1)", "-i", "b=normal(3, 0.2)", "-n", "500"]


def _run(tmp: Path) -> list[str]:
    return ["run", str(STUDIES / "ball_centre.toml"), "-n", "200", "-o", str(tmp / "r"), "-q"]


def _demo(tmp: Path) -> list[str]:
    return ["demo", "-o", str(tmp / "d"), "-n", "200", "-q"]


def _graph_run(_tmp: Path) -> list[str]:
    return ["graph", "run", str(GRAPHS / "bcs_origin.toml"), "-n", "200", "--place", "d_ac"]


def _graph_sweep(_tmp: Path) -> list[str]:
    vary = ["--vary", "probe.u_probe=0.001:0.002:2"]
    return [
        "graph",
        "sweep",
        str(GRAPHS / "ball_centre.toml"),
        *vary,
        "--quantity",
        "cx",
        "-n",
        "50",
    ]


def _verify_simulate(_tmp: Path) -> list[str]:
    # 40 trials: the fewest of whole-number 95 % intervals, as a study run reports them
    return ["verify", "simulate", str(STUDIES / "aguado2016.toml"), "-n", "40"]


def _verify_place(_tmp: Path) -> list[str]:
    study = str(STUDIES / "aguado2016.toml")
    return ["verify", "place", study, "-n", "2", "--grid", "2", "--refine", "0"]


def _artefact_simulate(_tmp: Path) -> list[str]:
    # 40 trials: the fewest of whole-number 95 % intervals, as a study run reports them
    return ["artefact", "simulate", str(STUDIES / "wang2022.toml"), "-n", "40", "--no-gum"]


def _positioning_evaluate(_tmp: Path) -> list[str]:
    data, study = STUDIES / "positioning_x.csv", STUDIES / "positioning_x.toml"
    return ["positioning", "evaluate", str(data), "--study", str(study), "-n", "50"]


def _circle_evaluate(tmp: Path) -> list[str]:
    rows = ["angle,direction,deviation"]
    for d in ("ccw", "cw"):
        rows += [f"{a},{d},{((a * 7) % 11) / 10}" for a in range(0, 360, 30)]
    (tmp / "trace.csv").write_text("\n".join(rows) + "\n", encoding="utf-8")
    return ["circle", "evaluate", str(tmp / "trace.csv"), "--radius", "100", "-n", "50"]


def _circle_simulate(_tmp: Path) -> list[str]:
    return ["circle", "simulate", str(STUDIES / "circle_c_axis.toml"), "-n", "50"]


#: A short run of every command that runs a Monte Carlo (its seed is added to it).
RUNS: dict[str, Callable[[Path], list[str]]] = {
    "propagate": _propagate,
    "run": _run,
    "demo": _demo,
    "graph run": _graph_run,
    "graph sweep": _graph_sweep,
    "verify simulate": _verify_simulate,
    "verify place": _verify_place,
    "artefact simulate": _artefact_simulate,
    "positioning evaluate": _positioning_evaluate,
    "circle evaluate": _circle_evaluate,
    "circle simulate": _circle_simulate,
}


def _call(argv: list[str], capsys: pytest.CaptureFixture[str]) -> str:
    code = main(argv)
    out, err = capsys.readouterr()
    assert code == 0, err
    return out


@pytest.mark.parametrize("path", sorted(_monte_carlo_commands()))
def test_a_monte_carlo_command_prints_its_seed_in_text_and_json(
    path: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setenv("COLUMNS", "200")
    monkeypatch.setattr(demo, "STUDIES", ("mass_calibration.toml",))
    assert path in RUNS, f"{path} runs a Monte Carlo: give it a short run in RUNS"
    argv = [*RUNS[path](tmp_path), "-s", str(SEED)]
    text = _call(argv, capsys)
    assert any("seed" in line and str(SEED) in line for line in text.splitlines()), text
    data = json.loads(_call([*argv, "--json"], capsys))  # the whole of stdout: one object
    seeds = [s["seed"] for s in data["studies"]] if path == "demo" else [data["seed"]]
    assert seeds == [SEED] * len(seeds), data
    assert seeds, data


def _printed_seed(text: str) -> int:
    found = re.findall(r"\bseed\b\D{0,40}?(\d+)", text)
    assert len(found) == 1, text
    return int(found[0])


@pytest.mark.parametrize("path", ["propagate", "graph run", "graph sweep"])
def test_a_seed_drawn_from_fresh_entropy_is_printed_and_repeats_the_run(
    path: str, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("COLUMNS", "200")
    argv = RUNS[path](tmp_path)
    first = _call(argv, capsys)
    seed = _printed_seed(first)
    again = _call([*argv, "--seed", str(seed)], capsys)
    assert again == first
    data = json.loads(_call([*argv, "-s", str(seed), "--json"], capsys))
    assert data["seed"] == seed


def test_u_and_U_are_labelled_and_the_json_states_its_units(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("COLUMNS", "200")
    argv = ["run", str(STUDIES / "ball_centre.toml"), "-n", "200", "-s", "3"]
    argv += ["-o", str(tmp_path / "r")]
    text = _call(argv, capsys)
    assert "U (k, p = 95 %)" in text
    assert re.search(r"│ p\.x +│ +-?[0-9.]+ │ +[0-9.]+ \(k = [0-9.]+\) │ mm +│", text), text
    data = json.loads(_call([*argv, "--json"], capsys))
    assert data["output"] == str(tmp_path / "r")
    assert (data["trials"], data["seed"], data["p"]) == (200, 3, 0.95)
    q = {q["name"]: q for q in data["quantities"]}["p.x"]
    assert q["unit"] == "mm"
    assert q["k"] == pytest.approx(q["U"] / q["u"])
    assert q["p"] == 0.95
    # verify simulate: standard uncertainties, labelled u, in µm, as its JSON keys say
    argv = ["verify", "simulate", str(STUDIES / "aguado2016.toml"), "-n", "40", "-s", "3"]
    text = _call(argv, capsys)
    assert "µm" in text.splitlines()[1]
    assert re.search(r"max [0-9.]+ \(u = [0-9.]+\)", text), text
    data = json.loads(_call([*argv, "--json"], capsys))
    assert {"estimate", "U", "k", "p", "u"} <= set(data["initial_ve_um"]["max"])
    assert data["unit"] == "µm"
    assert {c["unit"] for c in data["coefficients"].values()} <= {"µm", "µrad"}
    # demo: each study's line gives U with its unit, k and p
    monkeypatch.setattr(demo, "STUDIES", ("mass_calibration.toml",))
    text = _call(["demo", "-o", str(tmp_path / "d"), "-n", "200", "-s", "3", "-q"], capsys)
    line = text.splitlines()[0]
    assert re.search(r"U = [0-9.]+ mg \(k = [0-9.]+\) \(U at p = 95 %; seed 3; ", line), line
    # graph run: u in the graph's units in the table, its JSON in mm and rad, as it says
    argv = ["graph", "run", str(GRAPHS / "bcs_origin.toml"), "-n", "200", "--place", "d_ac"]
    data = json.loads(_call([*argv, "--json"], capsys))
    assert data["units"] == {"length": "mm", "angle": "rad"}


def _help_texts() -> Iterator[tuple[str, str]]:
    """(where, text) of every command's help and every option's help."""
    for path, cmd in _commands():
        yield path, cmd.help or ""
        for p in cmd.params:
            yield f"{path} {p.opts[0]}", getattr(p, "help", None) or ""


@pytest.mark.parametrize("path", sorted(COMMANDS))
def test_help_texts_are_printed_as_written(
    path: str, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    # Rich's markup once took "[run]" for a style tag and dropped it ("the study's  ndig"):
    # help is printed as plain text, every option's help as written (wrapped, not changed)
    monkeypatch.setenv("COLUMNS", "80")
    assert main([*path.split(), "--help"]) == 0
    shown = "".join(capsys.readouterr().out.split())
    for where, text in _help_texts():
        if where.startswith(path + " -"):
            assert "".join(text.split()) in shown, (where, text)


@pytest.mark.parametrize("path", sorted(COMMANDS))
def test_help_fits_80_columns_without_truncation(
    path: str, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("COLUMNS", "80")
    assert main([*path.split(), "--help"]) == 0
    out = capsys.readouterr().out
    assert "Usage: mtmc " + path in out
    for line in out.splitlines():
        assert len(line) <= 80, (path, line)
        assert "…" not in line, (path, line)  # a cell cut short
        assert "``" not in line, (path, line)  # reStructuredText of a docstring
        assert "\\[" not in line, (path, line)  # an escape of Rich markup


def _doc_rows() -> Iterator[tuple[str, str]]:
    """(first long option, where) of each row of docs/cli.md's table of shared options."""
    text = (ROOT / "docs" / "cli.md").read_text(encoding="utf-8")
    table = text.split("## Options shared by several commands", 1)[1].split("\n## ", 1)[0]
    for line in table.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) != 4 or cells[0] in ("option", "---"):
            continue
        names = re.findall(r"--[a-z-]+", cells[0])
        yield names[0], cells[3]


def test_the_table_of_shared_options_says_which_commands_have_each() -> None:
    # docs/cli.md's table against the commands themselves: an option added to or taken
    # from a command without the table changing fails here
    having: dict[str, set[str]] = defaultdict(set)
    for path, cmd in COMMANDS.items():
        for opt in _options(cmd):
            having[_longs(opt)[0]].add(path)
    rows = dict(_doc_rows())
    assert len(rows) >= 15, rows
    monte_carlo = set(_monte_carlo_commands())
    for option, where in rows.items():
        listed = set(re.findall(r"`([a-z]+(?: [a-z]+)?)`", where)) & set(COMMANDS)
        if where.startswith("every command that runs a Monte Carlo"):
            expected = monte_carlo
        elif where.startswith("all but"):
            expected = set(COMMANDS) - listed
        else:
            expected = listed
        assert having[option] == expected, (option, sorted(having[option] ^ expected))


#: The commands that run a study they build or load: their shared options come from one
#: declaration (mtmc.cli.run.study_command).
STUDY_COMMANDS = ("artefact simulate", "positioning evaluate", "circle simulate", "circle evaluate")


def _described(opt: Any) -> tuple[Any, ...]:
    return (opt.opts, opt.secondary_opts, opt.default, opt.help, _value_type(opt))


def test_the_study_commands_take_one_set_of_shared_options() -> None:
    # before, each command declared them itself, and -o said two things: "Also write the
    # result folder with its HTML report" (circle, positioning) and "Also write the result
    # folder (result.json, the study file, report.html) here; ..." (artefact, verify, propagate)
    from mtmc.cli.run import _STUDY_OPTIONS

    shared = {name for name, _kind, _option in _STUDY_OPTIONS}
    described = {
        path: {o.name: _described(o) for o in _options(COMMANDS[path]) if o.name in shared}
        for path in STUDY_COMMANDS
    }
    first = described[STUDY_COMMANDS[0]]
    assert set(first) == shared
    for path in STUDY_COMMANDS[1:]:
        assert described[path] == first, path
    # and -o means one thing wherever it writes a result folder with its report
    writers = ("propagate", "verify simulate", *STUDY_COMMANDS)
    helps = {
        path: next(o.help for o in _options(COMMANDS[path]) if "--output" in o.opts)
        for path in writers
    }
    assert len(set(helps.values())) == 1, helps
