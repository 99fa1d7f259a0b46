"""The Jenkins element as the one-slider limit of the Iwan, and the harmonic balance on it.

The peer benchmark (``benchmarks/bench_hb_peer.py``, pyHarm-os's Jenkins element) rests on
two facts checked here against independent routes, without the peer:

* ``IwanParameters(Fs, KT, 0, beta)`` with ``beta = 1e6`` is the Jenkins element (spring
  ``KT``, slip force ``Fs``) to ``1/beta`` of ``Fs``: the exact kernel on histories and on the
  steady periodic loops the harmonic balance uses, against a stepped Jenkins slider
  (``tests/_jenkins_bank.py``);
* :func:`~iwan_element.harmonic.harmonic_balance` of the Jenkins oscillator equals a
  harmonic balance written here with numpy and scipy's ``fsolve`` on the stepped slider
  (steady loop: three periods from rest, the last kept), through the stick-slip resonance.
"""

import numpy as np
import pytest
from _jenkins_bank import jenkins_bank
from scipy.optimize import fsolve

from iwan_element import IwanParameters
from iwan_element.core.masing import masing_constants, masing_history
from iwan_element.core.periodic import periodic_rows
from iwan_element.harmonic import ModalSystem, harmonic_balance

M, K, C, KT, FS = 1.0, 4.0e4, 8.0, 1.2e5, 10.0
PHI = FS / KT
BETA = 1e6
N = 64
HARM = (1, 3, 5)


def jenkins(u):
    return jenkins_bank(u, [KT], [PHI], 1.0)


@pytest.mark.parametrize("level", [0.5, 0.999, 2.0, 5.0])
def test_large_beta_iwan_is_the_jenkins_element(level):
    p = IwanParameters(FS, KT, 0.0, BETA)
    u = level * PHI * np.sin(np.linspace(0.0, 6 * np.pi, 1501))
    assert np.max(np.abs(masing_history(u, p)[0] - jenkins(u))) < 2.0 / BETA * FS
    tau = 2 * np.pi * np.arange(N) / N
    up = level * PHI * (np.cos(tau) + 0.3 * np.cos(3 * tau + 0.4))  # inner reversals
    F = periodic_rows(masing_constants(p, 0.0)[None, :], up[None, :])[0][0]
    assert np.max(np.abs(F - jenkins(np.tile(up, 3))[-N:])) < 2.0 / BETA * FS
    # and the limit is not trivially met: beta = 1e2 is 100x further off
    far = IwanParameters(FS, KT, 0.0, 1e2)
    if level > 1:
        assert np.max(np.abs(masing_history(u, far)[0] - jenkins(u))) > 20.0 / BETA * FS


def reference_hb(f_hz, force, start):
    """Harmonic balance of ``m x'' + c x' + k x + F_J(x) = force cos(W t)`` with the stepped
    Jenkins slider (x = sum a_h cos(h W t) + b_h sin(h W t), h = 1, 3, 5)."""
    W = 2 * np.pi * f_hz
    tau = 2 * np.pi * np.arange(N) / N
    E = np.column_stack([g(h * tau) for h in HARM for g in (np.cos, np.sin)])

    def res(c):
        x = E @ c
        fj = jenkins(np.tile(x, 3))[-N:]
        out = 2.0 / N * (E.T @ fj)
        for i, h in enumerate(HARM):
            a, b = c[2 * i], c[2 * i + 1]
            out[2 * i] += (K - M * (h * W) ** 2) * a + C * h * W * b
            out[2 * i + 1] += (K - M * (h * W) ** 2) * b - C * h * W * a
        out[0] -= force
        return out / force

    c = fsolve(res, start, xtol=1e-12)
    assert np.max(np.abs(res(c))) < 1e-9
    return c


@pytest.mark.parametrize("force", [3.0, 10.0])
def test_harmonic_balance_of_the_jenkins_oscillator(force):
    f = np.array([30.0, 45.0, 55.0, 60.0, 63.0, 70.0])
    system = ModalSystem.oscillator(M, K, C, IwanParameters(FS, KT, 0.0, BETA))
    r = harmonic_balance(system, frequency=f, force=force, harmonics=HARM, samples=N)
    assert r.converged.all()
    for k, fk in enumerate(f):
        Z = r.harmonics[k]
        ours = np.column_stack([Z.real, -Z.imag]).ravel()
        # start the reference a little off our solution: it must find the point itself
        ref = reference_hb(fk, force, ours * 1.05)
        A = np.hypot(ref[0], ref[1])
        assert r.amplitude[k] == pytest.approx(A, rel=2e-5)
        assert np.max(np.abs(ours - ref)) < 2e-5 * A  # the 3rd and 5th too
