"""The effects' element port in the compiled periodic kernel, against independent routes.

An effect stack around the modal form's zero element (or any stack of parallel effects that
declare their form) states its force as Masing rows plus history-free laws
(:class:`~iwan_element.core.periodic.PeriodicForm`); the harmonic balance then evaluates it
in the joints' kernel with its exact Jacobian instead of stepping the elements. Checked
here:

* the Jenkins bank's rows (:func:`~iwan_element.core.masing.jenkins_constants`) in the
  history kernel equal the Python bank stepped sample by sample, on random histories, to
  round-off; the stack's laws likewise;
* the form's steady loop equals the stepped element's steady loop (:func:`element_loop`),
  force and dissipation, on random periodic slips with inner reversals;
* the port's exact harmonic Jacobian against central finite differences;
* the declared tangents against finite differences of the declared forces;
* the harmonic balance through the compiled port equals the stepped route's.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from iwan_element.models.modal import ZeroElement

from iwan_element import IwanParameters
from iwan_element.core.masing import PM, jenkins_constants, masing_rows
from iwan_element.core.periodic import PeriodicForm
from iwan_element.effects import EFFECTS
from iwan_element.harmonic import ModalSystem, harmonic_balance
from iwan_element.harmonic.basis import Harmonics, check_harmonics, element_loop
from iwan_element.harmonic.system import ElementPort

#: A patch that starts to slide at 40 um (bins up to 320 um), a pin bearing after 60 um, a
#: cubic spring and a dashpot: every declared part of the form at once.
PATCH = {"k_2": 3e4, "u_s": 4e-5, "shape": 0.3, "u_e": 3.2e-4}
LAWS = (
    ("pinning_stiffness", {"k_p": 2e4, "delta": 6e-5}),
    ("hardening", {"k3": 4e11}),
    ("viscous_damping", {"c": 3.0}),
)


def _stack(laws=True):
    el = EFFECTS["macroslip_onset"](ZeroElement(), **PATCH)
    for name, vals in LAWS if laws else ():
        el = EFFECTS[name](el, **vals)
    return el


def _history(rng, n=400, x=3e-4):
    """A random walk with reversals of every size, from rest."""
    steps = rng.normal(size=n) * x / 8 * rng.choice([0.05, 1.0, 3.0], size=n)
    return np.clip(np.cumsum(steps), -1.3 * x, 1.3 * x)


class Stepped:
    """The element without its periodic form: the AFT steps it sample by sample."""

    def __init__(self, element):
        self.element = element

    def __getattr__(self, name):
        if name == "periodic_form":
            raise AttributeError(name)
        return getattr(self.element, name)


@pytest.mark.parametrize("seed", range(3))
def test_jenkins_rows_are_the_stepped_bank_on_random_histories(seed):
    rng = np.random.default_rng(seed)
    u = _history(rng)
    v = rng.normal(size=u.size) * 0.01
    el = _stack()
    form = el.periodic_form()
    assert form is not None and form.constants.shape[0] == 32 and len(form.laws) == 3
    F_rows = masing_rows(form.constants, np.tile(u, (32, 1)))[0].sum(axis=0)
    F_laws = sum(law(u, v)[0] for law in form.laws)
    F = F_rows - form.shift * u + F_laws
    ref = el.force_history(u, v)
    assert np.max(np.abs(F - ref)) <= 1e-12 * np.max(np.abs(ref))
    # the bank alone slides: its force differs from the stuck line by far more than that
    bank = _stack(laws=False).force_history(u)
    assert np.max(np.abs(bank)) > 1e3 * 1e-12 * np.max(np.abs(ref))


def test_jenkins_constants_refuse_bad_input():
    with pytest.raises(ValueError, match="phi"):
        jenkins_constants([1.0], [0.0])
    with pytest.raises(ValueError, match="k must"):
        jenkins_constants([-1.0], [1e-3])
    with pytest.raises(ValueError, match="tolerance"):
        PeriodicForm(np.vstack([jenkins_constants([1.0], [1e-3])] * 2) + np.eye(2, 15, 14))


@pytest.mark.parametrize("seed, scale", [(0, 1.0), (1, 1.0), (2, 0.4), (3, 0.4)])
def test_periodic_form_is_the_stepped_elements_steady_loop(seed, scale):
    """At ``scale = 0.4`` the upper Jenkins elements never slide (taken as their elastic
    line, not walked) while the lower ones do; at 1 every element slides."""
    rng = np.random.default_rng(20 + seed)
    b = Harmonics(*check_harmonics((0, 1, 2, 3, 5), 64))
    c = rng.normal(size=b.n_coefficients) * 1e-4
    c[1] += 2e-4  # a large fundamental with inner loops from the higher harmonics
    c *= scale
    W = 2 * math.pi * 80.0
    phi = _stack().periodic_form().constants[:, PM]
    stuck = int(np.sum(phi >= np.abs(b.E @ c).max()))
    assert (0 < stuck < phi.size) if scale < 1 else stuck == 0
    y, v = b.E @ c, W * (b.dE @ c)
    for laws in (False, True):
        el = _stack(laws)
        lp = el.periodic_form().loop(y, v)
        F, D = element_loop(el, y, v)
        assert np.max(np.abs(lp.force - F)) <= 1e-12 * np.max(np.abs(F))
        if not laws:  # the stepped dashpot integrates by trapezoids; the bank is exact
            assert lp.dissipation == pytest.approx(D, rel=1e-10)
            assert D > 0
    # the laws' work over the period as the AFT books it, (2 pi / N) sum f dy/dtau: the
    # dashpot's is c W pi sum h^2 |Y_h|^2 in closed form; the springs' is zero in the
    # continuum and only aliasing here
    dy = b.dE @ c
    amp2 = sum(h * h * (c[ia] ** 2 + c[ib] ** 2) for h, ia, ib in b.cols if h)
    visc = 3.0 * W * math.pi * amp2
    for law in _stack().periodic_form().laws:
        f = law(y, v)[0]
        work = 2 * math.pi / 64 * float(f @ dy)
        if law.cls.effect == "viscous_damping":
            assert work == pytest.approx(visc, rel=1e-12)
        else:
            assert abs(work) < 1e-2 * 2 * math.pi / 64 * float(np.abs(f) @ np.abs(dy))


def _port_system():
    joint = IwanParameters(Fs=5.0, KT=2e5, chi=-0.4, beta=0.3)
    base = ModalSystem.oscillator(1.0, 2.5e5, 4.0, joint)
    return base.with_ports([ElementPort(_stack(), 1.3)], [[base.modes[0, 0]]])


@pytest.mark.parametrize("seed", range(3))
def test_compiled_port_jacobian_matches_finite_differences(seed):
    rng = np.random.default_rng(40 + seed)
    sysm = _port_system()
    assert sysm.ports[0].form is not None
    b = Harmonics(*check_harmonics((0, 1, 2, 3, 5), 64))
    cz = rng.normal(size=(2, b.n_coefficients)) * 8e-5
    cz[:, 1] += 2e-4
    W = 2 * math.pi * 75.0
    _, J, _ = b.nonlinear_forces(sysm, cz, W)
    eps = 1e-11
    Jfd = np.zeros_like(J[1])
    for d in range(b.n_coefficients):
        cp, cm = cz.copy(), cz.copy()
        cp[1, d] += eps
        cm[1, d] -= eps
        Jfd[:, d] = b.nonlinear_forces(sysm, cp, W)[0][1] - b.nonlinear_forces(sysm, cm, W)[0][1]
        Jfd[:, d] /= 2 * eps
    np.testing.assert_allclose(J[1], Jfd, rtol=0, atol=1e-5 * np.abs(J[1]).max())
    # and the reversal columns matter: the tangent alone misses them
    y = b.E @ cz[1]
    lp = sysm.ports[0].form.loop(y, W * (b.dE @ cz[1]))
    diag_only = 1.3 * b.P @ ((lp.tangent - lp.shift + lp.law_du)[:, None] * b.E)
    assert np.abs(diag_only - Jfd).max() > 1e-2 * np.abs(J[1]).max()


@pytest.mark.parametrize("name, vals", LAWS)
def test_declared_tangents_are_the_derivatives_of_the_declared_forces(name, vals):
    cls = EFFECTS[name]
    rng = np.random.default_rng(7)
    u = rng.uniform(-2e-4, 2e-4, 50)
    v = rng.uniform(-0.05, 0.05, 50)
    fu, fv = (np.broadcast_to(x, u.shape) for x in cls.vector_tangent(u, v, **vals))
    h = 1e-10
    zero = np.zeros(u.shape)
    du = (cls.vector_force(zero, u + h, v, **vals) - cls.vector_force(zero, u - h, v, **vals)) / (
        2 * h
    )
    dv = (cls.vector_force(zero, u, v + h, **vals) - cls.vector_force(zero, u, v - h, **vals)) / (
        2 * h
    )
    scale = max(np.abs(fu).max(), 1.0)
    np.testing.assert_allclose(fu, du, rtol=0, atol=1e-6 * scale)
    np.testing.assert_allclose(fv, dv, rtol=0, atol=1e-6 * max(np.abs(fv).max(), 1.0))


def test_which_stacks_run_compiled():
    """Parallel effects with a declared form around a base that has one run compiled; a
    stack with any other layer (a gap in series, a slider law) steps its elements."""
    for name, vals in LAWS:
        assert EFFECTS[name](ZeroElement(), **vals).periodic_form() is not None
    assert _stack().periodic_form() is not None
    gap = EFFECTS["backlash"](_stack(), gap=1e-5)
    assert gap.periodic_form() is None
    assert EFFECTS["viscous_damping"](gap, c=1.0).periodic_form() is None
    assert ElementPort(Stepped(_stack()), 1.0).form is None
    assert "macroslip_onset" in _stack().describe()


def test_harmonic_balance_through_the_compiled_port_is_the_stepped_routes():
    sysm = _port_system()
    stepped = replace(sysm, ports=(ElementPort(Stepped(sysm.ports[0].element), 1.3),))
    f0 = sysm.omega[0] / (2 * math.pi)
    f = np.linspace(0.9 * f0, 1.1 * f0, 9)
    a = harmonic_balance(sysm, frequency=f, force=40.0)
    b = harmonic_balance(stepped, frequency=f, force=40.0)
    assert a.success and b.success
    np.testing.assert_allclose(a.amplitude, b.amplitude, rtol=1e-8)
    np.testing.assert_allclose(a.phase, b.phase, atol=1e-8)
    # the patch slides here (its force is not the stuck line): the check is not idle
    assert a.amplitude.max() > 3 * PATCH["u_s"] / sysm.modes[0, 0] * sysm.modes[-2, 0]
    assert np.all(np.abs(a.energy_error) < 1e-3)
