"""Issue 14, core items: small real reversals are never erased, extreme but valid parameters
compute (or are refused with a clear range error), and the CLI keeps its file outputs when its
printed output goes to a closed pipe."""

from __future__ import annotations

import math
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad

from iwan_element import (
    IwanJoint,
    IwanParameters,
    backbone,
    backbone_work,
    dissipation,
    secant_stiffness,
    tangent_stiffness,
)
from iwan_element.identify.loops.testdata import simulate_test

P = IwanParameters(Fs=1000.0, KT=1e6, chi=-0.5, beta=0.2)


def _forces(joint, u):
    out = []
    for x in u:
        out.append(joint.trial(x)[0])
        joint.commit()
    return np.array(out)


def _two_tiny_reversals(p, delta):
    """A large cycle 0 -> phi_max -> -0.3 phi_max with two reversals of size ``delta`` (relative
    to phi_max) on the way down, then up to 0.8 phi_max and down to -phi_max."""
    pts = [0.0, 1.0, -0.3, -0.3 + delta, -0.3 + delta / 2, 0.8, -1.0]
    return p.phi_max * np.concatenate([np.linspace(a, b, 40) for a, b in zip(pts[:-1], pts[1:])])


@pytest.mark.parametrize("tol", [1e-12, 1e-9, 1e-6, 1e-3])
def test_reversal_tol_never_erases_a_real_reversal(tol):
    """Reversals of 8e-4 phi_max are real (force change ~ KT * 8e-4 phi_max). A joint either
    refuses the tolerance or keeps them: its forces equal those of the exact model
    (reversal_tol=0) to round-off. Before the fix, tol=1e-3 was accepted and erased them."""
    u = _two_tiny_reversals(P, 8e-4)
    exact = _forces(IwanJoint(P, reversal_tol=0.0), u)
    try:
        j = IwanJoint(P, reversal_tol=tol)
    except ValueError as exc:
        assert "reversal_tol" in str(exc) and tol > 1e-9
        return
    F = _forces(j, u)
    assert np.max(np.abs(F - exact)) <= 1e-9 * P.Fs
    assert j.dissipated_energy == pytest.approx(_dissipated(u), rel=1e-12)


def _dissipated(u):
    j = IwanJoint(P, reversal_tol=0.0)
    _forces(j, u)
    return j.dissipated_energy


def test_tiny_reversals_agree_with_an_independent_slider_bank():
    """The exact model with the tiny loops against 20000 uniform sliders written here
    (force of each slider: clip(k (u - x_i), +-k phi_i)); error bound of a midpoint rule
    with the spike added exactly is well under 1e-3 Fs at these amplitudes."""
    u = _two_tiny_reversals(P, 8e-4)
    F = _forces(IwanJoint(P), u)
    n = 20000
    s = (np.arange(n) + 0.5) / n
    phi = P.phi_max * s
    k = (P.chi + 1.0) * P.K_slider * s**P.chi / n
    k = np.append(k, P.S)
    phi = np.append(phi, P.phi_max)
    x = np.zeros_like(k)
    bank = []
    for ui in u:
        x = np.clip(x, ui - phi, ui + phi)
        bank.append(np.sum(k * (ui - x)))
    assert np.max(np.abs(F - np.array(bank))) < 2e-3 * P.Fs


def test_reversal_tol_range_is_validated_and_named():
    with pytest.raises(ValueError, match=r"reversal_tol must be in \[0, 1e-09\]"):
        IwanJoint(P, reversal_tol=1e-3)
    IwanJoint(P, reversal_tol=1e-9)


@pytest.mark.parametrize(
    "u",
    [
        [-2.0e-2, 1.09804343e-230, 0.0, 1.09804343e-230],
        [0.0, -2e-2, 0.0, -1e-2, -1.043442e-224, -5e-3, 1e-300, -1e-300, 3e-3],
    ],
)
def test_reversals_of_any_magnitude_are_seen(u):
    """Found by the long property run: the walk tested ``d * du < 0``, which underflows to
    -0.0 for displacements of ~1e-230, so a reversal there was missed and the loop-closing
    test then popped the whole memory (force 1e-228 N instead of 0.5 N). Checked against an
    independent slider bank (exact here: chi = 0, beta = 0 gives uniform slip thresholds)."""
    p = IwanParameters(Fs=1.0, KT=100.0, chi=0.0, beta=0.0)  # phi_max = 0.02 m
    F = _forces(IwanJoint(p, reversal_tol=0.0), np.array(u))
    n = 4000
    phi = (np.arange(n) + 0.5) / n * p.phi_max  # rho = R: equal weights
    k = np.full(n, p.KT / n)
    x = np.zeros(n)
    bank = []
    for ui in u:
        x = np.clip(x, ui - phi, ui + phi)
        bank.append(np.dot(k, ui - x))
    assert np.allclose(F, bank, atol=p.KT * p.phi_max / n)


# ---------------------------------------------------------------- extreme parameters
@pytest.mark.parametrize("chi", [120.0, 500.0, 1e6])
@pytest.mark.parametrize("Fs, KT", [(1e3, 1e6), (1e-3, 1e9), (1e6, 1e3)])
def test_large_chi_computes_correctly(chi, Fs, KT):
    """chi >= 120 used to raise ZeroDivisionError/OverflowError (R = ... phi_max**-(chi+2)).
    Now every closed form is finite and agrees with an independent route: the backbone's
    numerical integral is backbone_work, and 8 int F - 4 u0 F(u0) is the dissipation
    (docs/equations.md section 2, any Masing model)."""
    p = IwanParameters(Fs, KT, chi, 0.1)
    pm = p.phi_max
    for r in (0.3, 0.999, 0.99999, 1.0, 2.0):
        u0 = r * pm
        F0 = backbone(u0, p)
        # the nonlinearity sits within ~1/chi of phi_max: break the integral up there
        knots = (
            [0.0] + [x for x in pm * (1.0 - np.logspace(-1, -9, 17)) if x < u0] + [min(u0, pm), u0]
        )
        work = sum(
            quad(lambda x: backbone(x, p), a, b, epsabs=0, epsrel=1e-13, limit=200)[0]
            for a, b in zip(knots[:-1], knots[1:])
            if b > a
        )
        assert backbone_work(u0, p) == pytest.approx(work, rel=1e-9)
        D = dissipation(u0, p)
        assert D == pytest.approx(8.0 * work - 4.0 * u0 * F0, rel=1e-6, abs=1e-12 * Fs * pm)
        assert math.isfinite(secant_stiffness(u0, p)) and math.isfinite(tangent_stiffness(u0, p))
    # large chi: the continuous density sits near phi_max, so the backbone is nearly linear
    assert backbone(0.5 * pm, p) == pytest.approx(0.5 * KT * pm, rel=1e-12)
    j = IwanJoint(p)
    for x in (0.5 * pm, -0.2 * pm, 2 * pm):
        j.trial(x)
        j.commit()
    assert j.force == pytest.approx(Fs) and math.isfinite(j.dissipated_energy)


def test_R_out_of_float_range_is_a_clear_error():
    p = IwanParameters(1e3, 1e6, 120.0, 0.1)
    with pytest.raises(ValueError, match="R = 10\\*\\*370.*outside the float range"):
        _ = p.R
    q = IwanParameters(1e3, 1e6, -0.5, 0.2)
    assert q.R == pytest.approx(8.784105e6, rel=1e-6)  # docs/equations.md section 5


@pytest.mark.parametrize(
    "kw, match",
    [
        (dict(Fs=1.0, KT=1.0, chi=2e6, beta=0.0), r"chi must be in \(-1, 1e\+06\]"),
        (dict(Fs=1e-300, KT=1e300, chi=-0.5, beta=0.0), "outside the float range: phi_max"),
        (dict(Fs=1e300, KT=1e-300, chi=-0.5, beta=0.0), "outside the float range: phi_max"),
        (dict(Fs=1e308, KT=1e308, chi=-0.5, beta=0.0), "outside the float range: KT phi_max"),
    ],
)
def test_parameters_outside_float_range_are_refused_clearly(kw, match):
    with pytest.raises(ValueError, match=match):
        IwanParameters(**kw)


# ---------------------------------------------------------------- CLI and a closed pipe
@pytest.fixture(scope="module")
def csv_path(tmp_path_factory):
    p = IwanParameters(9e3, 5e7, -0.5, 0.5)
    d = simulate_test(
        p, np.array([0.05, 0.1, 0.2, 0.3]) * 1e-3, cycles=2, sample_rate=5, force_noise=15.0, seed=0
    )
    path = tmp_path_factory.mktemp("pipe") / "test.csv"
    rows = "\n".join(f"{a:.2f},{b:.7f},{c:.6f}" for a, b, c in zip(d.t, d.u * 1e3, d.F * 1e-3))
    path.write_text("time [s],displacement [mm],force [kN]\n" + rows + "\n")
    return path


@pytest.mark.skipif(
    shutil.which("sh") is None or shutil.which("head") is None,
    reason="needs a POSIX shell with head and true",
)
@pytest.mark.parametrize("reader", ["true", "head -1"])
def test_cli_outputs_survive_a_closed_pipe(csv_path, tmp_path, reader):
    js, png = tmp_path / "r.json", tmp_path / "r.png"
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[1]), MPLBACKEND="Agg")
    cmd = (
        f"'{sys.executable}' -m iwan_element.cli fit '{csv_path}' --units mm,kN "
        f"--method dissipation --json '{js}' --plot '{png}' | {reader}"
    )
    res = subprocess.run(["sh", "-c", cmd], capture_output=True, text=True, env=env, timeout=300)
    assert "Traceback" not in res.stderr and "BrokenPipe" not in res.stderr, res.stderr
    assert js.stat().st_size > 100 and png.read_bytes()[:4] == b"\x89PNG"
