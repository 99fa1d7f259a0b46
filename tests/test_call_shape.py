"""One call shape (issue 46, point 9): simulations return result objects, never tuples, and
a function taking more than one physical quantity takes them by keyword."""

from __future__ import annotations

import inspect

import numpy as np
import pytest

import iwan_element as ie
from iwan_element import harmonic, models

#: (function, the physical quantities it takes) for every public function taking two or more
#: quantities that are settings of a run (the time series of a record stay positional, time
#: first, and the closed forms keep the paper's argument order)
KEYWORD_QUANTITIES = [
    (models.harmonic_balance, ("frequency", "force")),
    (models.frequency_response, ("force", "band")),
    (models.nonlinear_mode, ("amplitude", "mode")),
    (models.modal_amplitude_curve, ("amplitude",)),
    (harmonic.harmonic_balance, ("frequency", "force")),
    (harmonic.trace, ("force", "band")),
    (ie.modal_ringdown, ("K_inf", "q0", "v0", "zeta0", "mass")),
]


@pytest.mark.parametrize("fn, names", KEYWORD_QUANTITIES, ids=lambda x: getattr(x, "__name__", ""))
def test_physical_quantities_are_keyword_only(fn, names):
    params = inspect.signature(fn).parameters
    assert all(params[n].kind is inspect.Parameter.KEYWORD_ONLY for n in names), names


def test_modal_ringdown_returns_a_result_like_models_ringdown():
    """The same motion as before, now named: displacement, velocity, acceleration, with the
    package's result shape; the acceleration is the equation of motion's (independent of the
    integrator's own difference quotients)."""
    p = ie.IwanParameters(Fs=3.0, KT=2.5e4, chi=-0.5, beta=0.3)
    t = np.arange(800) / 4000.0
    K_inf, zeta0 = (2 * np.pi * 80.0) ** 2 - p.KT, 1e-3
    rd = ie.modal_ringdown(t, p, K_inf=K_inf, zeta0=zeta0, q0=2e-4)
    assert isinstance(rd, ie.ModalRingdown) and rd.success
    assert rd.report().splitlines()[0] == "usable"
    assert rd.t.shape == rd.displacement.shape == rd.velocity.shape == rd.acceleration.shape
    assert rd.displacement[0] == 2e-4 and rd.velocity[0] == 0.0
    # the velocity is the time derivative of the displacement (central differences, to the
    # step's second order)
    v_fd = np.gradient(rd.displacement, t)
    assert np.abs(v_fd[5:-5] - rd.velocity[5:-5]).max() < 0.02 * np.abs(rd.velocity).max()
    assert rd.linear_frequency == pytest.approx(80.0, rel=1e-12)
    with pytest.raises(TypeError):
        _q, _v, _a = rd  # not a tuple any more
