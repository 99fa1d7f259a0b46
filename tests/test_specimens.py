"""Specimen descriptions, presets, contact pressure and the linear matrices of the beam model."""

import dataclasses
import math

import numpy as np
import pytest
from iwan_element.models import preset
from iwan_element.models.modal.qsma import _interface_law
from iwan_element.models.reduced import contact_points, linear_system
from iwan_element.models.simulation import build_host
from iwan_element.models.specimens import PRESETS, Specimen, pressure_field

from iwan_element import backbone, tangent_stiffness

NAMES = ("example", "brake-reuss", "two-bolt-aluminium")


@pytest.mark.parametrize("name", NAMES)
def test_presets_are_frozen_validated_and_replaceable(name):
    s = preset(name)
    assert isinstance(s, Specimen) and s.name == name
    with pytest.raises(dataclasses.FrozenInstanceError):
        s.friction = 0.1
    v = dataclasses.replace(s, friction=0.15)
    assert v.friction == 0.15 and s.friction != 0.15
    assert s.replace(chi=-0.2).interface.chi == -0.2
    assert set(NAMES) <= set(PRESETS)


def test_published_geometry_of_the_thin_brake_reuss_beam():
    s = preset("brake-reuss")
    # docs/equations.md section 7: 72.0 cm long, lap 12 cm starting 30 cm from one end, acc3 at
    # 7.62 cm from the other end; cone radius at the interface 12.4 mm for t = 6.35 mm
    assert s.total_length == pytest.approx(0.72)
    assert s.lap_start == pytest.approx(0.30)
    assert s.total_length - s.sensor_position == pytest.approx(0.0762)
    assert s.cone_radius == pytest.approx(0.0124, abs=5e-5)
    assert s.boundary == "free-free" and len(s.bolt_positions) == 3
    a = preset("two-bolt-aluminium")
    assert (a.beam_length, a.width, a.thickness) == (0.27, 0.0254, 0.00635)
    assert a.boundary == "clamped-free" and a.excitation.kind == "shaker"
    assert a.excitation.position == pytest.approx(0.085)


@pytest.mark.parametrize(
    "change,match",
    [
        ({"beam_length": -1.0}, "beam_length"),
        ({"overlap": 0.5}, "overlap"),
        ({"bolt_positions": (0.2,)}, "bolt_positions"),
        ({"boundary": "pinned"}, "boundary"),
        ({"friction": float("nan")}, "friction"),
        ({"amplitude_range": (2e-6, 1e-6)}, "amplitude_range"),
        ({"chi": -1.5}, "chi"),
        ({"n_points": 1}, "n_points"),
        ({"sensor_position": 5.0}, "sensor"),
        ({"nonsense": 1.0}, "unknown"),
    ],
)
def test_bad_specimens_are_refused_with_the_argument_named(change, match):
    with pytest.raises(ValueError, match=match):
        preset("example").replace(**change)


@pytest.mark.parametrize("name", NAMES)
def test_pressure_integrates_to_the_bolt_loads_and_sets_slip_force_and_stiffness(name):
    s = preset(name)
    x, y, p = pressure_field(s)
    dA = (x[1] - x[0]) * (y[1] - y[0])
    assert p.sum() * dA == pytest.approx(len(s.bolt_positions) * s.preload, rel=1e-9)
    pts = contact_points(s)
    assert pts.normal_force.sum() == pytest.approx(len(s.bolt_positions) * s.preload, rel=1e-9)
    np.testing.assert_allclose(pts.Fs, s.friction * pts.normal_force, rtol=1e-12)
    np.testing.assert_allclose(pts.KT, s.interface.stiffness_per_area * pts.area, rtol=1e-12)
    # no contact beyond the cones: every point lies within r_c of a bolt (plus half a strip)
    half = 0.5 * s.overlap / s.interface.n_points
    d = np.min(np.abs((pts.x - s.lap_start)[:, None] - np.array(s.bolt_positions)[None, :]), axis=1)
    assert np.all(d <= s.cone_radius + half + 1e-12)
    # edges of the contact carry less pressure than the centre: they slip first
    p_i = pts.normal_force / pts.area
    assert p_i[0] < 0.5 * p_i.max() and p_i[-1] < 0.5 * p_i.max()
    assert pts.phi_max[0] < pts.phi_max.max()


def test_symmetric_bolt_layout_gives_a_symmetric_pressure_and_the_lumped_model_shares_equally():
    s = preset("brake-reuss")
    pts = contact_points(s)
    np.testing.assert_allclose(pts.normal_force, pts.normal_force[::-1], rtol=1e-9)
    lumped = contact_points(s.replace(model="lumped"))
    assert len(lumped) == 2 * len(s.bolt_positions)
    np.testing.assert_allclose(lumped.Fs, s.friction * s.preload / 2)


def test_pressure_exponent_stiffens_the_pressed_points():
    s = preset("brake-reuss")
    a = contact_points(s)
    b = contact_points(s.replace(stiffness_pressure_exponent=1.0))
    p = a.normal_force / a.area
    np.testing.assert_allclose(b.KT / a.KT, p / (a.normal_force.sum() / a.area.sum()), rtol=1e-12)


def test_vectorised_interface_law_equals_the_closed_forms_of_each_point():
    pts = contact_points(preset("brake-reuss"))
    p0 = pts.params[0]
    u = np.concatenate(
        [
            -np.geomspace(1e-9, 3 * pts.phi_max.max(), 7),
            np.geomspace(1e-9, 3 * pts.phi_max.max(), 7),
        ]
    )
    for p in (pts.params[0], pts.params[len(pts) // 2]):
        F, kt = _interface_law(u, p.Fs, p.KT, p.phi_max, p.chi, p.beta)
        np.testing.assert_allclose(F, backbone(u, p), rtol=1e-10, atol=1e-12 * p.Fs)
        inside = np.abs(u) < p.phi_max
        np.testing.assert_allclose(kt[inside], tangent_stiffness(u[inside], p), rtol=1e-10)
    assert p0.Fs > 0


@pytest.mark.parametrize("name", NAMES)
def test_the_exudyn_host_has_the_linear_systems_eigenvalues(name):
    """The Exudyn host (the linear system on slip coordinates, linear tangential springs)
    has the eigenvalues of ``(K0 + G^T diag(KT) G, M)``, computed by Exudyn itself."""
    s = preset(name)
    L = linear_system(s)
    pts = contact_points(s)
    import scipy.linalg as sla

    K = L.K0 + L.G.T @ (pts.KT[:, None] * L.G)
    w2 = sla.eigh(K, L.M, eigvals_only=True, subset_by_index=[0, 5])
    model = build_host(s, tangential="linear", floor=False)
    w2x, _ = model.mbs.ComputeODE2Eigenvalues(ignoreAlgebraicEquations=True, numberOfEigenvalues=6)
    elastic = np.sqrt(np.abs(w2)) > 2 * math.pi
    np.testing.assert_allclose(
        np.sqrt(np.abs(w2))[elastic], np.sqrt(np.abs(np.array(w2x)))[elastic], rtol=1e-6
    )
    # the interface stiffness matters: without it no elastic mode is stiffer, and one of the
    # first three is clearly softer
    n_rigid = 3 if s.boundary == "free-free" else 0
    w_stuck = np.sqrt(
        np.abs(sla.eigh(K, L.M, eigvals_only=True, subset_by_index=[0, n_rigid + 2]))
    )[n_rigid:]
    # (eigenvalue monotonicity: the k-th eigenvalue cannot rise when stiffness is removed)
    w_free = np.sqrt(
        np.abs(
            sla.eigh(L.K0 + 1e-6 * L.M, L.M, eigvals_only=True, subset_by_index=[0, n_rigid + 2])
        )
    )[n_rigid:]
    assert np.all(w_free <= w_stuck * (1 + 1e-9))
    assert np.min(w_free / w_stuck) < 0.99
