"""Physical ranges of the inputs of a positioning test: impossible environments are refused.

The reproducers are those of hostile use (air at 1000 °C, at 0.001 hPa, at 150 % humidity,
CO2 at -5 µmol/mol, a misalignment of uniform(-1e12, 1e12) µrad, which gave A = 8596 µm
from readings whose A is 2.1 µm): each was accepted and gave a number. The rule for a PDF
(``OUTSIDE``: its central 1 - 1e-6 interval inside the range) is checked against scipy's
quantiles, independently of the engine's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from mtmc.cli.main import main
from mtmc.errors import InputError
from mtmc.positioning import PositioningTest, UncertaintyModel, positioning_model
from mtmc.positioning.edlen import DOMAINS, EQUATIONS
from mtmc.positioning.uncertainty import INPUT_UNITS, OUTSIDE, physical_ranges
from mtmc.study import load_study
from mtmc.uncertainty.distributions import Distribution

ROOT = Path(__file__).resolve().parents[2]
STUDY = ROOT / "examples" / "studies" / "positioning_x.toml"
DATA = ROOT / "examples" / "studies" / "positioning_x.csv"
AIR = {"air_temperature": 20.0, "air_pressure": 1013.25, "humidity": 50.0}


def _model(**kw):
    return UncertaintyModel(**{**AIR, **kw})


@pytest.mark.parametrize(
    ("kw", "field", "span"),
    [
        ({"air_temperature": 1000.0}, "air_temperature", "-40 to 50 °C"),
        ({"air_pressure": 0.001}, "air_pressure", "600 to 1200 hPa"),
        ({"humidity": 150.0}, "humidity", "0 to 100 %"),
        ({"co2": -5.0}, "co2", "0 to 2000 µmol/mol"),
        ({"misalignment": "uniform(-1e12, 1e12)"}, "misalignment", "-10000 to 10000 µrad"),
    ],
)
def test_the_hostile_environments_are_refused(kw, field, span):
    with pytest.raises(InputError, match="physical range") as exc:
        _model(**kw)
    assert exc.value.field == field
    assert span in exc.value.message


@pytest.mark.parametrize(
    ("old", "new", "field", "span"),
    [
        ('"normal(20.8, 0.12)"', "1000", "environment.air_temperature_C", "-40 to 50 °C"),
        ('"normal(1008.2, 0.5)"', "0.001", "environment.air_pressure_hPa", "600 to 1200 hPa"),
        ('"normal(42, 4)"', "150", "environment.humidity_pct", "0 to 100 %"),
        ("co2_ppm = 450", "co2_ppm = -5", "environment.co2_ppm", "0 to 2000 µmol/mol"),
        (
            '"uniform(-50, 50)"',
            '"uniform(-1e12, 1e12)"',
            "instrument.misalignment_urad",
            "-10000 to 10000 µrad",
        ),
        ('"uniform(-1.0, 1.0)"', '"uniform(-2000, 2000)"', "environment.drift", "-1000 to 1000 µm"),
        ("resolution = 0.001", "resolution = 500", "instrument.resolution", "0 to 100 µm"),
        (
            "wavelength_nm = 632.991",
            "wavelength_nm = 200",
            "instrument.wavelength_nm",
            "to 1700 nm",
        ),
        ("dead_path_mm = 60.0", "dead_path_mm = 1e6", "instrument.dead_path_mm", "0 to 100000"),
    ],
)
def test_a_study_names_the_key_the_range_and_the_line(tmp_path, old, new, field, span):
    text = STUDY.read_text(encoding="utf-8")
    assert old in text
    path = tmp_path / "s.toml"
    path.write_text(text.replace(old, new), encoding="utf-8")
    (tmp_path / "positioning_x.csv").write_bytes(DATA.read_bytes())
    with pytest.raises(InputError, match="physical range") as exc:
        load_study(path)
    assert exc.value.field == field
    assert span in exc.value.message
    line = next(k for k, t in enumerate(path.read_text().splitlines(), 1) if new in t)
    assert exc.value.line == line


def test_the_cli_refuses_with_exit_2(tmp_path, capsys):
    text = STUDY.read_text(encoding="utf-8").replace('"normal(42, 4)"', "150")
    path = tmp_path / "s.toml"
    path.write_text(text, encoding="utf-8")
    (tmp_path / "positioning_x.csv").write_bytes(DATA.read_bytes())
    argv = ["positioning", "evaluate", str(tmp_path / "positioning_x.csv"), "--study", str(path)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "humidity_pct" in err
    assert "0 to 100 %" in err


def test_a_normal_pdf_is_held_to_its_central_interval():
    # scipy's quantile: mean ± 4.8916 sd holds 1 - 1e-6 of a normal PDF
    z = float(stats.norm.ppf(1.0 - 0.5 * OUTSIDE))
    assert z == pytest.approx(4.8916, abs=1e-4)
    sd = 1.0
    inside = 50.0 - z * sd - 1e-6  # the upper end of the range of the air temperature
    _model(air_temperature=f"normal({inside!r}, {sd})")
    with pytest.raises(InputError, match=r"central 99\.9999 % lies in") as exc:
        _model(air_temperature=f"normal({inside + 2e-6!r}, {sd})")
    assert "bounded one" in exc.value.message
    # near a hard limit, a bounded PDF is the one to give: dry air measured to ±1 % RH
    with pytest.raises(InputError, match="humidity"):
        _model(humidity="normal(2, 1)")
    _model(humidity="uniform(0, 4)")
    _model(humidity="triangular(0, 4, 2)")


def test_a_heavy_tailed_pdf_reaches_further():
    # a t PDF of 2 degrees of freedom: its 1 - 5e-7 quantile is about 1000 scales out
    q = float(stats.t.ppf(1.0 - 0.5 * OUTSIDE, 2))
    assert q > 900.0
    _model(air_temperature=f"t(2, 20, {25.0 / q!r})")
    with pytest.raises(InputError, match="air_temperature"):
        _model(air_temperature=f"t(2, 20, {35.0 / q!r})")


@dataclass(frozen=True, eq=False)
class _NoQuantile(Distribution):
    """A scalar PDF without a quantile function (its draws are never taken here)."""

    mu: float
    sigma: float

    @property
    def mean(self) -> float:
        return self.mu

    @property
    def std(self) -> float:
        return self.sigma

    def sample(self, rng, n, **_):  # pragma: no cover - never drawn
        return rng.normal(self.mu, self.sigma, n)


def test_a_pdf_without_quantiles_is_held_to_chebyshev():
    # Pr(|X - μ| >= kσ) <= 1/k²: k = 1000 bounds the probability outside to 1e-6
    k = 1.0 / math.sqrt(OUTSIDE)
    assert k == pytest.approx(1000.0)
    _model(co2=_NoQuantile(1000.0, 0.999))
    with pytest.raises(InputError, match="co2"):
        _model(co2=_NoQuantile(1000.0, 1.001))


def test_drift_and_resolution_in_the_test_unit():
    x = np.zeros((3, 5, 2))
    lin = PositioningTest([0.0, 500.0, 1000.0], x, unit="um")
    rot = PositioningTest([0.0, 90.0, 180.0], x, unit="arcsec", target_unit="deg")
    positioning_model(lin, UncertaintyModel(drift="uniform(-999, 999)", resolution=100.0))
    with pytest.raises(InputError, match=r"-1000 to 1000 µm") as exc:
        positioning_model(lin, UncertaintyModel(drift="uniform(-1001, 1001)"))
    assert exc.value.field == "drift"
    with pytest.raises(InputError, match="0 to 100 µm") as exc:
        positioning_model(lin, UncertaintyModel(resolution=101.0))
    assert exc.value.field == "resolution"
    positioning_model(rot, UncertaintyModel(drift="uniform(-360, 360)"))
    with pytest.raises(InputError, match="-360 to 360 arcsec"):
        positioning_model(rot, UncertaintyModel(drift="uniform(-361, 361)"))
    mm = PositioningTest([0.0, 500.0, 1000.0], x, unit="mm")
    with pytest.raises(InputError, match=r"0 to 0\.1 mm"):
        positioning_model(mm, UncertaintyModel(resolution=0.2))
    urad = PositioningTest([0.0, 90.0, 180.0], x, unit="urad", target_unit="deg")
    ranges = physical_ranges(unit="urad")
    # 0.1° and 0.01° in µrad
    assert ranges["drift"][1] == pytest.approx(math.pi / 1800.0 * 1e6, rel=1e-15)
    assert ranges["resolution"][1] == pytest.approx(math.pi / 18000.0 * 1e6, rel=1e-15)
    with pytest.raises(InputError, match="µrad"):
        positioning_model(urad, UncertaintyModel(resolution=200.0))


def test_each_equation_takes_its_own_wavelengths():
    # Ciddor's dispersion covers 300 nm; the Edlén forms are taken from 350 nm
    _model(wavelength_nm=300.0, equation="ciddor")
    for eq in EQUATIONS[1:]:
        with pytest.raises(InputError, match="350 to 1700 nm") as exc:
            _model(wavelength_nm=300.0, equation=eq)
        assert exc.value.field == "wavelength_nm"


def test_every_input_has_a_range_and_a_reason():
    ranges = physical_ranges("ciddor", "um")
    assert set(INPUT_UNITS) | {"dead_path_mm", "wavelength_nm", "drift", "resolution"} == set(
        ranges
    )
    for low, high, why in ranges.values():
        assert low < high
        assert len(why) > 20
    d = DOMAINS["ciddor"]
    assert ranges["air_pressure"][:2] == (d.pressure_Pa[0] / 100.0, d.pressure_Pa[1] / 100.0)
    # the shipped study is well inside every range
    load_study(STUDY)


def test_a_typical_laser_setup_passes_at_the_limits_of_a_shop():
    # a warm humid shop with a free-running laser and a carbon-fibre axis: all accepted
    UncertaintyModel(
        air_temperature="normal(35, 0.2)",
        air_pressure="normal(950, 1)",
        humidity="uniform(80, 95)",
        co2="uniform(400, 1200)",
        equation_error="normal(0, 0.02)",
        wavelength_error="uniform(-2, 2)",
        material_temperature="normal(38, 0.5)",
        expansion="uniform(-1.5, 0.5)",
        misalignment="uniform(-500, 500)",
        dead_path_mm=2000.0,
        air_temperature_change="uniform(-1, 1)",
        air_pressure_change="uniform(-3, 3)",
        drift="uniform(-20, 20)",
        resolution=0.01,
    )
