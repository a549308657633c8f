"""Fig. 7 of Wang, Cheung and Kong 2022: drawn without touching the process's Matplotlib."""

from __future__ import annotations

import sys
from pathlib import Path

import matplotlib
import pytest

from mtmc.artefact.plot import plot_error_vectors
from mtmc.artefact.simulation import simulate_artefact
from mtmc.study import load_study

STUDY = Path(__file__).resolve().parents[2] / "examples" / "studies" / "wang2022.toml"


def test_drawn_without_pyplot_or_a_backend_choice(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    def chosen(*_: object, **__: object) -> None:
        raise AssertionError("a library call chose the process's Matplotlib backend")

    monkeypatch.setattr(matplotlib, "use", chosen)
    monkeypatch.delitem(sys.modules, "matplotlib.pyplot", raising=False)
    backend = dict.__getitem__(matplotlib.rcParams, "backend")
    run = simulate_artefact(load_study(STUDY).study, trials=20, seed=1, gum_too=False)
    svg = plot_error_vectors(run, tmp_path / "fig7.svg", magnification=5000.0)
    png = plot_error_vectors(run, tmp_path / "fig7.png")
    assert "matplotlib.pyplot" not in sys.modules
    assert dict.__getitem__(matplotlib.rcParams, "backend") == backend
    text = svg.read_text()
    assert "magnified 5000 times" in text
    assert "(c) 3D view" in text
    assert png.read_bytes().startswith(b"\x89PNG")
