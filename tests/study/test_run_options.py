"""Every run option reachable from a study file and the command line, and constant outputs.

- an output with u = 0 is reported (u = 0, no plot of one value, the JCGM 101 §8 verdict
  "not applicable") by every kind that can give one, through ``mtmc run``;
- ``[run] nan_policy`` / ``--nan-policy`` leave out the trials whose model value is not
  finite and say how many;
- ``[run] trials = "adaptive"`` / ``--adaptive`` / ``run_graph(adaptive=True)`` stop by
  the rule of JCGM 101 §7.9.4, checked here from the kept samples.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from mtmc.cli.main import main
from mtmc.errors import InputError
from mtmc.graph import load_graph, run_graph
from mtmc.study import load_study
from mtmc.uncertainty.montecarlo import monte_carlo

ROOT = Path(__file__).resolve().parents[2]
GRAPHS = ROOT / "examples" / "graphs"

#: A graph whose output ``c`` is the mean of two given numbers: a constant.
CONSTANT_GRAPH = """\
title = "constant"
units = "mm"

[[place]]
name = "a"
type = "real"
value = 1.0

[[place]]
name = "b"
type = "real"
value = 3.0

[[transition]]
name = "t1"
op = "middle"
in = ["a", "b"]
out = "c"
"""


def _write(folder: Path, name: str, text: str) -> Path:
    path = folder / name
    path.write_text(text, encoding="utf-8")
    return path


def _run(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    code = main(["run", *args])
    cap = capsys.readouterr()
    return code, cap.out, cap.err


def _result(out: Path) -> dict:
    return json.loads((out / "result.json").read_text(encoding="utf-8"))


# ----------------------------------------------------------------------------------------
# constant outputs


def _check_constant(q: dict, value: float) -> None:
    """A quantity of result.json with u = 0: its statement, verdict and no histogram."""
    assert q["monte_carlo"]["u"] == 0.0
    assert q["monte_carlo"]["estimate"] == pytest.approx(value, abs=1e-12)
    assert q["monte_carlo"]["k"] is None
    assert q["monte_carlo"]["symmetric"] == [q["monte_carlo"]["estimate"]] * 2
    assert q["validation"]["verdict"] == "not applicable"
    assert q["validation"]["passed"] is None
    assert q["histogram"] == {"edges": [], "density": []}


def test_constant_propagate_study_is_reported(tmp_path, capsys):
    study = _write(
        tmp_path, "s.toml", 'kind = "propagate"\nmodel = "a"\n[inputs]\na = 2\n[run]\ntrials = 50\n'
    )
    out = tmp_path / "out"
    code, text, err = _run(capsys, str(study), "-o", str(out), "--seed", "1")
    assert code == 0, err
    assert "not applicable" in text  # the CLI summary line of y
    q = _result(out)["quantities"][0]
    _check_constant(q, 2.0)
    page = (out / "report.html").read_text(encoding="utf-8")
    assert "u(y) = 0: every one of the 50 trials gave y = 2" in page
    assert 'data-plot="histogram:y"' not in page
    assert 'data-plot="convergence:y"' not in page
    assert '<span class="na">not applicable</span>' in page


def test_constant_graph_study_is_reported(tmp_path, capsys):
    _write(tmp_path, "g.toml", CONSTANT_GRAPH)
    study = _write(
        tmp_path,
        "s.toml",
        'kind = "graph"\ngraph = "g.toml"\noutputs = ["c"]\n[run]\ntrials = 50\nseed = 3\n',
    )
    out = tmp_path / "out"
    code, text, err = _run(capsys, str(study), "-o", str(out))
    assert code == 0, err
    assert "not applicable" in text
    _check_constant(_result(out)["quantities"][0], 2.0)  # (1 + 3) / 2
    page = (out / "report.html").read_text(encoding="utf-8")
    assert "u(c) = 0: every one of the 50 trials gave c = 2 mm" in page


def test_kinematics_study_with_no_error_on_z_is_reported(tmp_path, capsys):
    # a location error of the C axis in x moves the tool in x and y (C at 90 and 45 deg),
    # never in z: z is the commanded value in every trial, x and y are uncertain
    study = _write(
        tmp_path,
        "k.toml",
        'kind = "kinematics"\nmachine = "table-table"\nangles = "deg"\n'
        "poses = [[150.0, 0.0, -100.0, 0.0, 90.0], [100.0, 50.0, -50.0, 0.0, 45.0]]\n"
        '[errors]\nEX0C = "normal(0, 0.003)"\n[run]\ntrials = 400\nseed = 2\n',
    )
    out = tmp_path / "out"
    code, _, err = _run(capsys, str(study), "-o", str(out))
    assert code == 0, err
    qs = {q["name"]: q for q in _result(out)["quantities"]}
    for z in (qs["pose1.z"], qs["pose2.z"]):
        _check_constant(z, z["gum"]["estimate"])
    moving = [n for n in ("pose1.x", "pose1.y", "pose2.x") if qs[n]["monte_carlo"]["u"] > 0]
    assert moving  # the error acts on the others: they keep their plots and verdicts
    for n in moving:
        assert qs[n]["validation"]["verdict"] != "not applicable"
        assert len(qs[n]["histogram"]["edges"]) > 1
    page = (out / "report.html").read_text(encoding="utf-8")
    assert "u(pose1.z) = 0: every one of the 400 trials" in page
    assert f'data-plot="histogram:{moving[0]}"' in page


# ----------------------------------------------------------------------------------------
# nan_policy

#: log of an input that is not positive in some trials (about 2.3 % of them: Φ(-2))
LOG_STUDY = """\
kind = "propagate"
model = "log(a)"
[inputs]
a = "normal(1, 0.5)"
[run]
trials = 4000
seed = 11
"""


def _bad_trials() -> tuple[int, float]:
    """The trials of LOG_STUDY whose log is not finite, and u of the others, from the inputs.

    The same seed draws the same inputs whatever the model (the engine's seeding); here
    the inputs themselves are the model, and numpy takes their log.
    """
    a = np.asarray(monte_carlo(lambda a: a, {"a": "normal(1, 0.5)"}, 4000, 11).samples)
    good = a > 0
    return int((~good).sum()), float(np.std(np.log(a[good]), ddof=1))


def test_nan_policy_in_the_study_file_leaves_out_and_counts(tmp_path, capsys):
    bad, u_good = _bad_trials()
    assert 40 < bad < 150  # 4000 Φ(-2) ≈ 91: the study has bad trials to leave out
    study = _write(tmp_path, "s.toml", LOG_STUDY + 'nan_policy = "omit"\n')
    out = tmp_path / "out"
    code, text, err = _run(capsys, str(study), "-o", str(out))
    assert code == 0, err
    r = _result(out)
    assert r["run"]["omitted"] == bad
    assert r["run"]["nan_policy"] == "omit"
    assert r["quantities"][0]["monte_carlo"]["omitted"] == bad
    # the same finite values: equal to rounding of the summation order
    assert r["quantities"][0]["monte_carlo"]["u"] == pytest.approx(u_good, rel=1e-12)
    assert f"{bad} of 4000 trials left out" in text
    assert f"{bad}</span> of them left out" in (out / "report.html").read_text(encoding="utf-8")


def test_nan_policy_option_overrides_the_file(tmp_path, capsys):
    bad, _ = _bad_trials()
    study = _write(tmp_path, "s.toml", LOG_STUDY)
    out = tmp_path / "out"
    code, _, err = _run(capsys, str(study), "-o", str(out))
    assert code == 2
    # the advice names what a user of mtmc run can set, not the Python keyword
    assert "--nan-policy omit" in err
    assert '[run] nan_policy = "omit"' in err
    assert "nan_policy='omit'" not in err
    assert not out.exists()
    code, _, err = _run(capsys, str(study), "-o", str(out), "--nan-policy", "omit")
    assert code == 0, err
    assert _result(out)["run"]["omitted"] == bad
    code, _, err = _run(capsys, str(study), "-o", str(out), "--nan-policy", "skip")
    assert code == 2
    assert "--nan-policy" in err
    assert "'skip'" in err


def test_nan_policy_in_the_file_is_checked(tmp_path):
    study = _write(tmp_path, "s.toml", LOG_STUDY + 'nan_policy = "skip"\n')
    with pytest.raises(InputError) as e:
        load_study(study)
    assert e.value.file == str(study)
    assert e.value.line == 8
    assert e.value.field == "run.nan_policy"
    assert "'raise'" in e.value.message
    assert "'omit'" in e.value.message


# ----------------------------------------------------------------------------------------
# adaptive Monte Carlo


def _coverage_indices(m: int, p: float) -> tuple[int, int]:
    """JCGM 101 §7.7.2 (0-based): the ends ỹ_r, ỹ_{r+q} of the symmetric interval."""
    q = int(p * m + 0.5)  # pM rounded (an integer for M = 10⁴, p = 0.95)
    r = int((m - q) / 2 + 0.5)
    return r - 1, r + q - 1


def _tolerance(u: float, ndig: int) -> float:
    """JCGM 101 §7.9.2: u as c × 10^l with c of ndig digits; δ = 10^l / 2."""
    exp = math.floor(math.log10(abs(u))) - ndig + 1
    if round(u / 10.0**exp) >= 10**ndig:  # rounding gave one digit more (9.96 -> 10)
        exp += 1
    return 0.5 * 10.0**exp


def _stopped_by_the_rule(y: np.ndarray, h: int, p: float, ndig: int) -> list[bool]:
    """For n = 2..N blocks of h values of y (N h, d): is JCGM 101 §7.9.4 met after n?"""
    y = y.reshape(y.shape[0], -1)
    lo_i, hi_i = _coverage_indices(h, p)
    stats = []
    for b in range(y.shape[0] // h):
        blk = np.sort(y[b * h : (b + 1) * h], axis=0)
        stats.append(np.stack([blk.mean(axis=0), blk.std(axis=0, ddof=1), blk[lo_i], blk[hi_i]]))
    s = np.array(stats)  # (N, 4, d)
    met = []
    for n in range(2, len(stats) + 1):
        sd = s[:n].std(axis=0, ddof=1) / math.sqrt(n)
        u_all = y[: n * h].std(axis=0, ddof=1)
        delta = np.array([_tolerance(float(u), ndig) for u in u_all])
        met.append(bool(np.all(2.0 * sd <= delta)))
    return met


#: y = x with u(x) = 3: ndig = 2 gives δ = 0.05 (u = 3.0), and the interval ends of
#: blocks of 10⁴ trials scatter by about 0.08: the rule needs about ten blocks
ADAPTIVE_STUDY = """\
kind = "propagate"
model = "x"
[inputs]
x = "normal(10, 3)"
[run]
trials = "adaptive"
ndig = 2
seed = 21
samples = true
"""


def test_adaptive_study_stops_by_the_rule_of_7_9(tmp_path, capsys):
    study = _write(tmp_path, "s.toml", ADAPTIVE_STUDY)
    assert load_study(study).settings.adaptive
    out = tmp_path / "out"
    code, text, err = _run(capsys, str(study), "-o", str(out))
    assert code == 0, err
    r = _result(out)
    run = r["run"]
    h = 10_000  # JCGM 101 §7.9.4 a): max(100/(1 - p), 10⁴) for p = 0.95
    assert run["adaptive"] is True
    assert run["ndig"] == 2
    assert r["trials"] == run["trials"] == run["blocks"] * h
    y = np.load(out / "samples" / "y.npy")
    assert y.shape == (r["trials"],)
    met = _stopped_by_the_rule(y, h, 0.95, 2)
    # it stopped at the first n >= 2 where the rule holds, and not before
    assert met[-1]
    assert not any(met[:-1])
    assert run["blocks"] > 3  # the rule, not the minimum of two blocks, stopped it
    assert run["tolerance"] == pytest.approx(0.05)
    assert "adaptive Monte Carlo (JCGM 101 §7.9)" in text
    # its u agrees with a fixed run of 10⁶ trials within δ: both scatter by less than
    # u/sqrt(2M) <= 0.007, δ = 0.05 (JCGM 101 §7.9.2: u to ndig digits)
    fixed = monte_carlo(lambda x: x, {"x": "normal(10, 3)"}, 10**6, 5)
    assert abs(r["quantities"][0]["monte_carlo"]["u"] - fixed.u) <= run["tolerance"]
    page = (out / "report.html").read_text(encoding="utf-8")
    assert "adaptive procedure of JCGM 101 §7.9" in page


def test_adaptive_option_of_mtmc_run(tmp_path, capsys):
    fixed_file = ADAPTIVE_STUDY.replace('trials = "adaptive"', "trials = 1000")
    study = _write(tmp_path, "s.toml", fixed_file)
    out = tmp_path / "out"
    code, _, err = _run(capsys, str(study), "-o", str(out), "--adaptive")
    assert code == 0, err
    r = _result(out)
    assert r["run"]["adaptive"]
    assert r["trials"] % 10_000 == 0
    assert r["trials"] >= 20_000
    y = np.load(out / "samples" / "y.npy")
    assert _stopped_by_the_rule(y, 10_000, 0.95, 2)[-1]
    # --trials on the adaptive file gives a fixed run; with --adaptive it is refused
    adaptive = _write(tmp_path, "a.toml", ADAPTIVE_STUDY)
    code, _, err = _run(capsys, str(adaptive), "-o", str(out), "-n", "300")
    assert code == 0, err
    assert _result(out)["trials"] == 300
    assert _result(out)["run"]["adaptive"] is False
    code, _, err = _run(capsys, str(study), "-o", str(out), "--adaptive", "-n", "300")
    assert code == 2
    assert "--adaptive" in err
    assert "--trials" in err


def test_adaptive_kinematics_covers_every_reported_output(tmp_path):
    # three coordinates of two poses; the run stops when all six have converged
    study = _write(
        tmp_path,
        "k.toml",
        'kind = "kinematics"\nmachine = "table-table"\nangles = "deg"\n'
        "poses = [[150.0, 0.0, -100.0, -30.0, 45.0], [100.0, 50.0, -50.0, -45.0, 90.0]]\n"
        '[errors]\nEX0C = "normal(0, 0.003)"\nEY0A = "normal(0, 0.005)"\n'
        'EZ0A = "normal(0, 0.005)"\n[run]\ntrials = "adaptive"\nndig = 1\nseed = 4\n',
    )
    r = load_study(study).run(samples=True)
    run = r.extra["run"]
    assert run["adaptive"]
    assert r.trials == run["blocks"] * 10_000
    met = _stopped_by_the_rule(np.asarray(r.samples["tool_positions"]), 10_000, 0.95, 1)
    assert met[-1]
    assert not any(met[:-1])


def test_run_graph_adaptive_stops_when_every_place_has_converged():
    g = load_graph(GRAPHS / "ball_centre.toml")
    res = run_graph(g, seed=3, outputs=["p"], keep=["p"], adaptive=True, ndig=1)
    assert res.adaptive
    assert res.trials == res.blocks * 10_000
    assert res.tolerance is not None
    met = _stopped_by_the_rule(np.asarray(res.samples["p"]), 10_000, 0.95, 1)
    assert met[-1]
    assert not any(met[:-1])
    # the same seed run for the same number of trials gives the same numbers
    fixed = run_graph(g, res.trials, 3, outputs=["p"])
    # the same values, summed in another order (pooled blocks, seed-block moments)
    np.testing.assert_allclose(fixed.places["p"].u_vector, res.places["p"].u_vector, rtol=1e-12)
    with pytest.raises(InputError, match="adaptive"):
        run_graph(g, 1000, 3, adaptive=True)


def test_graph_study_and_mtmc_graph_run_adaptive(tmp_path, capsys):
    study = _write(
        tmp_path,
        "s.toml",
        f'kind = "graph"\ngraph = "{GRAPHS / "ball_centre.toml"}"\noutputs = ["p"]\n'
        '[run]\ntrials = "adaptive"\nndig = 1\nseed = 3\n',
    )
    r = load_study(study).run()
    direct = run_graph(
        load_graph(GRAPHS / "ball_centre.toml"), seed=3, adaptive=True, ndig=1, outputs=["p"]
    )
    assert r.trials == direct.trials
    assert r.extra["run"]["blocks"] == direct.blocks
    assert (
        main(
            [
                "graph",
                "run",
                str(GRAPHS / "ball_centre.toml"),
                "--adaptive",
                "-s",
                "3",
                "--place",
                "p",
                "--json",
            ]
        )
        == 0
    )
    data = json.loads(capsys.readouterr().out)
    # ndig 2 (the command's) needs at least the trials of ndig 1
    assert data["adaptive"] is True
    assert data["trials"] >= direct.trials
    assert data["trials"] == data["blocks"] * 10_000


def test_sweep_refuses_adaptive_naming_the_field(tmp_path):
    study = _write(
        tmp_path,
        "s.toml",
        f'kind = "sweep"\ngraph = "{GRAPHS / "bcs_origin.toml"}"\n'
        '[run]\ntrials = "adaptive"\nseed = 5\n'
        '[sweep]\noutput = "d_ac"\ntrials = 200\n[sweep.vary]\n"probe.u_probe" = "0.001:0.005:3"\n',
    )
    with pytest.raises(InputError) as e:
        load_study(study)
    assert (e.value.file, e.value.line, e.value.field) == (str(study), 4, "run.trials")
    assert "grid" in e.value.message
    assert "JCGM 101 §7.9" in e.value.message
    fixed = _write(tmp_path, "f.toml", study.read_text().replace('"adaptive"', "300"))
    with pytest.raises(InputError) as e:
        load_study(fixed).run(adaptive=True)
    assert e.value.field == "adaptive"


def test_trials_text_other_than_adaptive_is_refused(tmp_path):
    study = _write(tmp_path, "s.toml", ADAPTIVE_STUDY.replace('"adaptive"', '"many"'))
    with pytest.raises(InputError) as e:
        load_study(study)
    assert e.value.field == "run.trials"
    assert e.value.line == 6
    assert '"adaptive"' in e.value.message


# ----------------------------------------------------------------------------------------
# the other kinds that run the engine

STUDIES = ROOT / "examples" / "studies"


def _shipped(name: str, old: str, new: str):
    """A shipped study with one line changed, read from its own folder."""
    from mtmc.study import loads_study

    text = (STUDIES / name).read_text(encoding="utf-8")
    assert old in text
    return loads_study(text.replace(old, new), file=name, folder=STUDIES)


def test_positioning_study_adaptive_stops_by_the_rule():
    s = _shipped("positioning_x.toml", "trials = 200000", 'trials = "adaptive"\nndig = 1')
    r = s.run(samples=True)
    run = r.extra["run"]
    assert run["adaptive"]
    assert r.trials == run["blocks"] * 10_000
    y = np.stack([np.asarray(r.samples[q.name]) for q in r.quantities], axis=1)
    # the rule holds for the reported parameters when the run stops (it may have held for
    # some of them earlier: the engine waits for all its outputs)
    assert _stopped_by_the_rule(y, 10_000, 0.95, 1)[-1]


def test_artefact_study_takes_nan_policy():
    s = _shipped("wang2022.toml", "trials = 10000", 'trials = 200\nnan_policy = "omit"')
    assert s.settings.nan_policy == "omit"
    run = s.run(seed=1).extra["run"]
    assert run["nan_policy"] == "omit"
    assert run["omitted"] == 0  # the simulated probing gives finite values in every trial


@pytest.mark.parametrize(
    ("new", "field", "said"),
    [
        ('trials = "adaptive"', "run.trials", "whole verifications"),
        ('nan_policy = "omit"\ntrials = 1000', "run.nan_policy", "cannot leave out trials"),
    ],
)
def test_verification_refuses_what_it_does_not_offer(new, field, said):
    with pytest.raises(InputError) as e:
        _shipped("aguado2016.toml", "trials = 1000", new)
    assert e.value.field == field
    assert e.value.file == "aguado2016.toml"
    assert e.value.line is not None
    assert said in e.value.message


def test_adaptive_run_of_a_constant_stops_at_two_blocks(tmp_path, capsys):
    # u = 0: no digit of u to settle (JCGM 101 §7.9.2 gives no δ), the rule's minimum of
    # two blocks ends the run, and the constant is reported as in a fixed run
    study = _write(
        tmp_path,
        "s.toml",
        'kind = "propagate"\nmodel = "a"\n[inputs]\na = 2\n[run]\ntrials = "adaptive"\n',
    )
    out = tmp_path / "out"
    code, _, err = _run(capsys, str(study), "-o", str(out), "-s", "1")
    assert code == 0, err
    r = _result(out)
    assert r["run"]["blocks"] == 2
    assert r["trials"] == 20_000
    _check_constant(r["quantities"][0], 2.0)


def test_mtmc_run_names_the_option_a_kind_refuses(tmp_path, capsys):
    study = _write(
        tmp_path,
        "s.toml",
        f'kind = "sweep"\ngraph = "{GRAPHS / "bcs_origin.toml"}"\n[run]\ntrials = 300\n'
        '[sweep]\noutput = "d_ac"\ntrials = 200\n[sweep.vary]\n"probe.u_probe" = "0.001:0.005:3"\n',
    )
    code, _, err = _run(capsys, str(study), "-o", str(tmp_path / "out"), "--adaptive")
    assert code == 2
    assert err.startswith("mtmc: error: --adaptive: a sweep study has no adaptive Monte Carlo")


def test_mtmc_propagate_gum_of_a_constant_is_not_applicable(capsys):
    assert main(["propagate", "a", "-i", "a=constant(2)", "-n", "100", "-s", "1", "--gum"]) == 0
    assert "not applicable" in capsys.readouterr().out
    args = ["propagate", "a", "-i", "a=constant(2)", "-n", "100", "-s", "1", "--gum", "--json"]
    assert main(args) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["u"] == 0.0
    assert data["validation"]["passed"] is None
