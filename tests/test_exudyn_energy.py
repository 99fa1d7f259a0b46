"""The energy-balance helper for a user's own Exudyn model (``iwan_element.exudyn.energy``),
each claim checked against an independent route: the initial energy in closed form, the
external work against the reference Newmark integrator's ``int F v dt``, and a damper the
balance does not book shown as an error."""
from __future__ import annotations

import math

import numpy as np
import pytest
from _connector_models import Chain, newmark_reference, settings
from exudyn.itemInterface import CoordinateSpringDamper

from iwan_element import IwanJoint, IwanParameters
from iwan_element.exudyn import add_iwan_connector, record_energy

P = IwanParameters(Fs=1000.0, KT=1e6, chi=-0.5, beta=0.2)
H, N = 2e-5, 1500


def test_free_decay_holds_its_initial_energy():
    m, k, v0 = 1.0, 1e5, 1.5
    chain = Chain([m], v0=[v0])
    chain.spring(-1, 0, k)
    conn = chain.joint(-1, 0, P)                 # IwanParameters build the exact joint
    rec = record_energy(chain.mbs, conn)
    chain.solve(settings(H, N))
    bal = rec.balance()
    assert isinstance(conn.joint, IwanJoint)
    assert bal.kinetic[0] == pytest.approx(0.5 * m * v0 ** 2, rel=1e-12)
    assert np.all(bal.external_work == 0.0)
    assert bal.joint_dissipated[-1] > 0.05 * bal.kinetic[0]    # the joint slipped
    assert bal.max_error < 1e-4 and bal.success  # the joint work by quadrature
    np.testing.assert_array_equal(bal.t, conn.time_history)


def test_external_work_equals_the_reference_integrators():
    f0, omega = 400.0, 2 * math.pi * 50.0
    chain = Chain([1.0])
    chain.harmonic_force(0, f0, omega)
    conn = chain.joint(-1, 0, IwanJoint(P))
    rec = record_energy(chain.mbs, [conn])
    chain.solve(settings(H, N))
    bal = rec.balance()
    t, _, v = newmark_reference([1.0], [(-1, 0, IwanJoint(P))], h=H, n_steps=N,
                                force=lambda t: np.array([f0 * math.sin(omega * t)]))
    p = f0 * np.sin(omega * t) * v[:, 0]
    work = float(np.sum(0.5 * (p[1:] + p[:-1]) * np.diff(t)))
    assert bal.external_work[-1] == pytest.approx(work, rel=1e-6)
    assert bal.max_error < 1e-4 and bal.success  # the joint work by quadrature
    assert "usable" in bal.report().splitlines()[0]


def test_an_unbooked_damper_shows_as_an_error():
    chain = Chain([1.0], v0=[1.5])
    mbs = chain.mbs
    mbs.AddObject(CoordinateSpringDamper(markerNumbers=[chain.ground_marker, chain.markers[0]],
                                         stiffness=1e5, damping=50.0))
    conn = chain.joint(-1, 0, P)
    rec = record_energy(mbs, conn)
    chain.solve(settings(H, N))
    bal = rec.balance()
    assert not bal.success and bal.max_error > 1e-2
    assert "damper" in bal.verdict()


def test_bad_arguments_are_refused():
    chain = Chain([1.0])
    with pytest.raises(ValueError, match="joints must be"):
        record_energy(chain.mbs, [])
    with pytest.raises(ValueError, match="mbs must be"):
        record_energy(None, [])
    with pytest.raises(ValueError, match="IwanParameters"):
        add_iwan_connector(chain.mbs, [chain.ground_marker, chain.markers[0]], object())
    conn = chain.joint(-1, 0, P)
    rec = record_energy(chain.mbs, conn)
    with pytest.raises(RuntimeError, match="nothing recorded"):
        rec.balance()
