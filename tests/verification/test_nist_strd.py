"""NIST StRD non-linear regression problems solved by the batched least-squares layer.

Both starts of each file are solved in one batched call; the certified parameters and
residual sum of squares must be matched to at least 6 significant digits. Files:
``tests/reference/nist_strd/`` (provenance in ``tests/reference/README.md``).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from mtmc.verification.lsq import STATUS, least_squares

DATA = Path(__file__).parent.parent / "reference" / "nist_strd"


def read_strd(name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float]:
    """x, y, starts (2, P), certified (P,), certified residual sum of squares."""
    lines = (DATA / f"{name}.dat").read_text().splitlines()
    starts, cert = [], []
    for ln in lines:
        m = re.match(r"\s*b\d+\s*=\s*(\S+)\s+(\S+)\s+(\S+)\s+(\S+)", ln)
        if m:
            starts.append([float(m.group(1)), float(m.group(2))])
            cert.append(float(m.group(3)))
    rss = next(float(ln.split(":")[1]) for ln in lines if ln.startswith("Residual Sum of Squares"))
    i = next(k for k, ln in enumerate(lines) if re.match(r"\s*Data:\s+y\s+x", ln))
    data = np.array([[float(v) for v in ln.split()] for ln in lines[i + 1 :] if ln.strip()])
    return data[:, 1], data[:, 0], np.array(starts).T, np.array(cert), rss


def _model(name: str, x: np.ndarray):  # type: ignore[no-untyped-def]
    """Model value and analytic Jacobian, batched over parameter rows b (M, P)."""

    def f(b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        c = [b[:, k : k + 1] for k in range(b.shape[1])]
        if name in ("Misra1a", "BoxBOD"):
            e = np.exp(-c[1] * x)
            return c[0] * (1 - e), np.stack([1 - e, c[0] * x * e], axis=-1)
        if name == "MGH09":
            num, den = x**2 + x * c[1], x**2 + x * c[2] + c[3]
            v = c[0] * num / den
            return v, np.stack([num / den, c[0] * x / den, -v * x / den, -v / den], axis=-1)
        if name == "Eckerle4":
            z = (x - c[2]) / c[1]
            g = np.exp(-0.5 * z * z)
            v = c[0] / c[1] * g
            return v, np.stack(
                [g / c[1], -c[0] / c[1] ** 2 * g + v * z * z / c[1], v * z / c[1]], axis=-1
            )
        if name == "Bennett5":
            base = c[1] + x
            v = c[0] * base ** (-1 / c[2])
            return v, np.stack(
                [v / c[0], -v / (c[2] * base), v * np.log(base) / c[2] ** 2], axis=-1
            )
        if name == "Thurber":
            num = c[0] + c[1] * x + c[2] * x**2 + c[3] * x**3
            den = 1 + c[4] * x + c[5] * x**2 + c[6] * x**3
            v = num / den
            cols = [x**0 / den, x / den, x**2 / den, x**3 / den]
            cols += [-v * x / den, -v * x**2 / den, -v * x**3 / den]
            return v, np.stack(cols, axis=-1)
        raise AssertionError(name)

    return f


@pytest.mark.parametrize("name", ["Misra1a", "Thurber", "MGH09", "BoxBOD", "Eckerle4", "Bennett5"])
def test_certified_values_from_both_starts(name: str) -> None:
    x, y, starts, cert, rss = read_strd(name)
    f = _model(name, x)
    res = least_squares(lambda b, _: f(b)[0] - y, lambda b, _: f(b)[1], starts, max_iter=2000)
    assert res.converged.all(), res.messages()
    rel = np.abs(res.x - cert) / np.abs(cert)
    assert rel.max() < 1e-6, (name, rel.max(axis=1))
    assert np.allclose(2 * res.cost, rss, rtol=1e-8, atol=0)


def test_certified_standard_deviations() -> None:
    """The covariance s²(JᵀJ)⁻¹ gives NIST's certified standard deviations (Misra1a)."""
    x, y, starts, _, _ = read_strd("Misra1a")
    f = _model("Misra1a", x)
    res = least_squares(lambda b, _: f(b)[0] - y, lambda b, _: f(b)[1], starts[:1])
    u = np.sqrt(np.diag(res.covariance()[0]))
    assert np.allclose(u, [2.7070075241e00, 7.2668688436e-06], rtol=1e-6)


def test_a_start_that_stops_early_says_so() -> None:
    x, y, starts, _, _ = read_strd("MGH09")
    f = _model("MGH09", x)
    res = least_squares(lambda b, _: f(b)[0] - y, lambda b, _: f(b)[1], starts, max_iter=3)
    assert res.status.tolist() == [0, 0]
    assert res.messages()[0] == STATUS[0]
    assert not res.converged.any()
