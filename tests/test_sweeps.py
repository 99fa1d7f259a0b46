"""Raw stepped-sine sweeps read as one nonlinear mode (iwan_element.sweep_curve).

Independent route: the single-mode oscillator with the exact Iwan joint
(``iwan_element.IwanJoint``) is driven by ``F cos(W t)`` and integrated in time (central
differences) to steady state at every step of a sweep; the fundamental is taken by a DFT
over whole periods. The drive point sees the mode through its shape value ``PHI`` (modal
constant ``c = PHI**2``) plus a mass-line residual of rigid-body modes, ``-C_RB / W**2``,
added to the fundamental exactly (a linear, uncoupled contribution). The truth is the modal
Iwan closed form (``modal_iwan_curve``, first-harmonic stiffness, dashpot floor) at the
modal amplitude ``X / PHI``: it is not made by the code under test.
"""

import math
import re
from pathlib import Path

import numpy as np
import pytest

from iwan_element import IwanJoint, IwanParameters, fit_modal_iwan, modal_iwan_curve, sweep_curve

F0, KAPPA, CHI, BETA, PHIMAX, ZETA0 = 50.0, 0.15, -0.5, 0.5, 1e-3, 0.008
PHI, C_RB = 0.8, 1.0  # mode shape at the drive point; rigid-body residual
W02 = (2 * math.pi * F0) ** 2
_KT = KAPPA * W02
P = IwanParameters(_KT * (BETA + (CHI + 1) / (CHI + 2)) * PHIMAX / (1 + BETA), _KT, CHI, BETA)
K_INF = W02 - _KT
STEPS = 160  # time steps per period: frequency error 6e-5


def truth(X):
    """True frequency [Hz] and damping ratio at sensor displacement amplitude X [m]."""
    return modal_iwan_curve(
        np.asarray(X) / PHI, P, K_inf=K_INF, zeta0=ZETA0, stiffness="harmonic", floor="dashpot"
    )


def simulate_sweep(freqs, forces, settle=100, record=8):
    """Stepped sine on the modal oscillator; returns the complex fundamental X / F per step.

    At each step the force keeps its phase continuous, the oscillator runs ``settle``
    periods (the first step three times as many) and the fundamental of ``PHI q`` relative
    to the force is taken by a DFT over the next ``record`` whole periods.
    """
    joint = IwanJoint(P)
    trial, commit = joint.trial, joint.commit
    c = 2.0 * ZETA0 * math.sqrt(W02)
    q = v = theta = Fj = 0.0
    out = []
    for j, (f, Fa) in enumerate(zip(freqs, forces)):
        W = 2 * math.pi * f
        h = 2 * math.pi / (W * STEPS)
        q_prev = q - h * v
        cp, cm = 1.0 + 0.5 * c * h, 1.0 - 0.5 * c * h
        n_settle = STEPS * settle * (3 if j == 0 else 1)
        acc = 0.0j
        for i in range(n_settle + STEPS * record):
            force = PHI * Fa * math.cos(theta)
            q_next = (2.0 * q - cm * q_prev + h * h * (force - K_INF * q - Fj)) / cp
            Fj, _ = trial(q_next)
            commit()
            q_prev, q = q, q_next
            theta += W * h
            if i >= n_settle:
                acc += q * complex(math.cos(theta), -math.sin(theta))
        v = (q - q_prev) / h
        theta %= 2 * math.pi
        out.append(PHI * 2.0 * acc / (STEPS * record) / Fa - C_RB / W**2)
    return np.array(out)


def _rows(levels):
    """Stack per-sweep (f, F, H) into the arrays sweep_curve takes (acceleration, +pi)."""
    lab, f, F, H = (
        np.concatenate(x)
        for x in zip(*[(np.full(len(fl), i), fl, Fl, Hl) for i, (fl, Fl, Hl) in enumerate(levels)])
    )
    W = 2 * math.pi * f
    # accelerance A/F = -W^2 H: amplitude |H| F W^2, phase angle(H) + pi
    return lab, f, F, np.abs(H) * F * W**2, np.angle(-H)


@pytest.fixture(scope="module")
def force_controlled():
    """Four force-controlled sweeps; the force drops by 35 % at each sweep's resonance."""
    Q = np.array([0.05, 0.15, 0.3, 0.5]) * PHIMAX
    fq, zq = truth(Q * PHI)
    f = np.linspace(fq[-1] * (1 - 3 * zq[-1]), fq[0] * (1 + 3 * zq[0]), 21)
    levels = []
    for q, fr, zr in zip(Q, fq, zq):
        F = (
            q
            * 2
            * zr
            * (2 * math.pi * fr) ** 2
            / PHI
            * (1 - 0.35 * np.exp(-(((f - fr) / (2 * zr * fr)) ** 2)))
        )
        levels.append((f, F, simulate_sweep(f, F)))
    return _rows(levels)


@pytest.fixture(scope="module")
def response_controlled():
    """Three sweeps whose force is set from the closed forms to hold the response."""
    X_target = np.array([0.04, 0.15, 0.45]) * PHIMAX * PHI
    levels = []
    for X in X_target:
        fr, zr = truth(X)
        f = fr * (1 + np.linspace(-2.5, 2.5, 15) * zr)
        W, wr = 2 * math.pi * f, 2 * math.pi * fr
        H = PHI**2 / (wr**2 - W**2 + 2j * zr * wr * W) - C_RB / W**2
        F = X / np.abs(H)
        levels.append((f, F, simulate_sweep(f, F)))
    return _rows(levels)


def _check_truth(curve, f_tol, z_tol):
    ft, zt = truth(curve.amplitude)
    assert np.all(np.abs(curve.frequency / ft - 1) < f_tol), curve.frequency / ft - 1
    assert np.all(np.abs(curve.damping_ratio / zt - 1) < z_tol), curve.damping_ratio / zt - 1
    # the stated standard errors are not wildly optimistic: within 5 sigma + the form bias
    assert np.all(np.abs(curve.frequency - ft) < 5 * curve.frequency_std + 1e-4 * ft)


def test_force_controlled_sweeps_give_the_modal_iwan_curve(force_controlled):
    lab, f, F, A, ph = force_controlled
    assert np.ptp(F[lab == 3]) / F[lab == 3].max() > 0.3  # the force is not held
    curve = sweep_curve(f, F, A, ph, level=lab, quantity="acceleration")
    assert curve.method == "stepped-sine-sweep" and len(curve) >= 6
    assert (
        curve.amplitude.min() < 0.05 * PHIMAX * PHI and curve.amplitude.max() > 0.25 * PHIMAX * PHI
    )
    # viscous-form inversion of a mode whose damping is partly hysteretic: about 2 % in
    # damping (measured 1.6-2.6 %), 5e-4 in frequency
    _check_truth(curve, 5e-4, 0.04)
    assert "accelerance-like" in curve.notes and not curve.warnings
    c = float(re.search(r"modal constant c = ([0-9.eE+-]+)", curve.notes).group(1))
    assert c == pytest.approx(PHI**2, rel=0.03)  # fitted, not given


def test_response_controlled_sweeps(response_controlled):
    lab, f, F, A, ph = response_controlled
    X = A / (2 * math.pi * f) ** 2
    for i in range(3):  # the response is held to 6 %
        assert np.ptp(np.log(X[lab == i])) < 0.06
    curve = sweep_curve(f, F, A, ph, level=lab)
    assert len(curve) == 3
    _check_truth(curve, 5e-4, 0.04)


def test_phase_conventions_agree(force_controlled):
    """Receptance-like, accelerance-like, velocity-like and conjugated phases: one curve."""
    lab, f, F, A, ph = force_controlled
    W = 2 * math.pi * f
    ref = sweep_curve(f, F, A, ph, level=lab)
    X = A / W**2
    for resp, phase, quantity, word in (
        (X, ph - math.pi, "displacement", "receptance-like"),
        (A / W, ph - math.pi / 2, "velocity", "velocity-like"),
        (A, -ph, "acceleration", "conjugated"),
        (A, ph - math.pi, "acceleration", "inverted"),
    ):  # sensor mounted upside down
        c = sweep_curve(f, F, resp, np.angle(np.exp(1j * phase)), level=lab, quantity=quantity)
        assert word in c.notes
        np.testing.assert_allclose(c.frequency, ref.frequency, rtol=1e-9)
        np.testing.assert_allclose(c.damping_ratio, ref.damping_ratio, rtol=1e-6)


def test_phase_that_cannot_be_told_is_refused(force_controlled):
    lab, f, F, A, ph = force_controlled
    with pytest.raises(ValueError, match="convention cannot be told"):
        sweep_curve(f, F, A, ph + math.pi / 4, level=lab)  # half-way between classes
    with pytest.raises(ValueError, match="only .* rad along the sweeps"):
        sweep_curve(f, F, A, np.full_like(ph, 0.3), level=lab)  # flat phase
    far = f > 50.0  # above every resonance: no peak inside
    with pytest.raises(ValueError, match="peak inside"):
        sweep_curve(f[far], F[far], A[far], ph[far], level=lab[far])
    with pytest.raises(ValueError, match="degrees"):
        sweep_curve(f, F, A, np.degrees(ph), level=lab)


def test_bad_input_and_no_mutation(force_controlled):
    lab, f, F, A, ph = force_controlled
    before = [a.copy() for a in (lab, f, F, A, ph)]
    sweep_curve(f, F, A, ph, level=lab)
    for a, b in zip((lab, f, F, A, ph), before):
        np.testing.assert_array_equal(a, b)
    bad_F = F.copy()
    bad_F[3] = np.nan
    with pytest.raises(ValueError, match="F contains NaN"):
        sweep_curve(f, bad_F, A, ph, level=lab)
    with pytest.raises(ValueError, match="F must be > 0"):
        sweep_curve(f, -F, A, ph, level=lab)
    with pytest.raises(ValueError, match="same length"):
        sweep_curve(f, F[:-1], A, ph, level=lab)
    with pytest.raises(ValueError, match="quantity"):
        sweep_curve(f, F, A, ph, level=lab, quantity="strain")
    with pytest.raises(ValueError, match="level must hold one label"):
        sweep_curve(f, F, A, ph, level=lab[:-1])
    with pytest.raises(ValueError, match="peak_fraction"):
        sweep_curve(f, F, A, ph, level=lab, peak_fraction=0.0)
    with pytest.raises(ValueError, match="bins must be an integer"):
        sweep_curve(f, F, A, ph, level=lab, bins=2.5)
    with pytest.raises(ValueError, match="degree must be"):
        sweep_curve(f, F, A, ph, level=lab, degree=9)


def test_sweeps_without_labels_split_where_frequency_turns(force_controlled):
    lab, f, F, A, ph = force_controlled
    o = np.concatenate([np.flatnonzero(lab == i)[:: (1 if i % 2 == 0 else -1)] for i in range(4)])
    c = sweep_curve(f[o], F[o], A[o], ph[o])  # up, down, up, down
    ref = sweep_curve(f, F, A, ph, level=lab)
    np.testing.assert_allclose(c.damping_ratio, ref.damping_ratio, rtol=1e-6)


def test_sweep_curve_feeds_fit_modal_iwan(force_controlled):
    lab, f, F, A, ph = force_controlled
    fit = fit_modal_iwan(sweep_curve(f, F, A, ph, level=lab))
    f0 = math.sqrt(W02) / (2 * math.pi)
    assert abs(fit.parameters["f0"] / f0 - 1) < 2e-3
    assert abs(fit.parameters["chi"] - CHI) < 0.15


# ---------------------------------------------------------------- real BRB sweeps (GPL data)
def _shared(*parts):
    here = Path(__file__).resolve().parents[2] / "shared" / "data"
    for root in (here, Path("/work/shared/data")):
        if root.joinpath(*parts).is_file():
            return root.joinpath(*parts)
    return None


SWEEPS = _shared("brb-steppedsine-fc", "fc_sweeps.csv")
HAMMER = _shared("brb-hammer", "hammer_acc3.csv")


@pytest.mark.skipif(
    SWEEPS is None or HAMMER is None,
    reason="GPL-3.0 BRB data are read from ../shared only; not present here",
)
def test_real_brb_sweeps_against_the_hammer_curve():
    """The four force-controlled sweeps give one curve over about 20-275 um that joins the
    hammer ring-down of the same point where they overlap: within 0.15 % in frequency (the
    two tests were made on different set-ups; the data README expects about 0.1 Hz) and
    within 35 % in damping (README: 10-20 % between test types; measured here 20-29 %)."""
    from iwan_element.models.calibration import measured_amplitude_curve

    from iwan_element import read_sweep_csv

    sweep = sweep_curve(**read_sweep_csv(SWEEPS))
    hammer = measured_amplitude_curve(HAMMER)
    assert "receptance-like" in sweep.notes and not sweep.warnings
    assert sweep.amplitude.min() < 30e-6 and sweep.amplitude.max() > 230e-6
    # damping rises with amplitude (microslip) over the whole curve
    assert np.all(np.diff(sweep.damping_ratio) > -2 * sweep.damping_ratio_std[1:])
    assert sweep.damping_ratio[-1] > 2.5 * sweep.damping_ratio[0]
    X = hammer.amplitude
    inside = (X >= sweep.amplitude.min()) & (X <= sweep.amplitude.max())
    assert inside.sum() >= 3
    lx = np.log(sweep.amplitude)
    f_s = np.interp(np.log(X[inside]), lx, sweep.frequency)
    z_s = np.interp(np.log(X[inside]), lx, sweep.damping_ratio)
    assert np.all(np.abs(f_s / hammer.frequency[inside] - 1) < 1.5e-3)
    assert np.all(np.abs(z_s / hammer.damping_ratio[inside] - 1) < 0.35)
    # and the curve goes into the modal Iwan fit as it is
    fit = fit_modal_iwan(sweep)
    assert 80.0 < fit.parameters["f0"] < 81.0


def test_noisy_sweeps_stay_within_their_stated_errors(force_controlled):
    """1 % amplitude and 0.01 rad phase noise (seeded): the curve stays near the truth and the
    stated standard errors cover the error (within 3 sigma plus the 2 % form bias)."""
    lab, f, F, A, ph = force_controlled
    rng = np.random.default_rng(7)
    A_n = A * (1 + 0.01 * rng.standard_normal(A.size))
    F_n = F * (1 + 0.01 * rng.standard_normal(F.size))
    ph_n = ph + 0.01 * rng.standard_normal(ph.size)
    curve = sweep_curve(f, F_n, A_n, ph_n, level=lab)
    ft, zt = truth(curve.amplitude)
    assert np.all(np.abs(curve.frequency - ft) < 3 * curve.frequency_std + 2e-4 * ft)
    assert np.all(np.abs(curve.damping_ratio - zt) < 3 * curve.damping_ratio_std + 0.03 * zt)
    assert np.all(curve.damping_ratio_std < 0.1 * zt)


def test_a_resonance_narrower_than_the_frequency_step_is_refused_naming_it():
    """A linear mode with zeta = 1e-4 at 80 Hz swept in 0.05 Hz steps: its half-power width
    (2 zeta f = 0.016 Hz) is a third of the step, so only the point at the peak lies above 0.2
    of it (the neighbours at +-0.05 Hz are at 0.16, from the closed-form receptance). Was: a
    ValueError about an empty 'amplitude' the caller never gave."""
    f = np.arange(79.2, 81.2001, 0.05)
    w, w0, z = 2 * np.pi * f, 2 * np.pi * 80.0, 1e-4
    H = 0.5 / (w0**2 - w**2 + 2j * z * w0 * w)
    F = np.full(f.size, 0.1)
    A = np.abs(H) * F * w**2
    assert np.sum(np.abs(H) >= 0.2 * np.abs(H).max()) == 1  # the truth of the case
    with pytest.raises(ValueError, match=r"peak_fraction: only 1 point.*sweep more finely"):
        sweep_curve(f, F, A, np.angle(H))
    # the same mode swept finely is read (the refusal is about the steps, not the mode)
    f2 = np.arange(79.9, 80.1001, 0.002)
    w2 = 2 * np.pi * f2
    H2 = 0.5 / (w0**2 - w2**2 + 2j * z * w0 * w2)
    c = sweep_curve(f2, np.full(f2.size, 0.1), np.abs(H2) * 0.1 * w2**2, np.angle(H2))
    np.testing.assert_allclose(c.frequency, 80.0, rtol=1e-5)
