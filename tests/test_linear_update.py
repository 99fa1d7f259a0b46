"""Linear model updating (models/updating/) and the test setup built into the linear system
(models/specimens/setups.py, models/linear/system.py): sensitivities against finite
differences of the whole modal solution, a setup against closed forms, and the update of a
synthetic specimen back to its known truth."""

import math

import numpy as np
import pytest
from iwan_element.models import (
    Clamp,
    Excitation,
    PointMass,
    Setup,
    Shaker,
    linear_update,
    natural_frequencies,
    preset,
    updatable,
)
from iwan_element.models.beam import element_matrices
from iwan_element.models.linear import LinearSystem, attach_setup
from iwan_element.models.updating import (
    modal_sensitivities,
    modal_state,
    pair_modes,
    with_parameters,
)
from scipy.linalg import eigh
from scipy.optimize import brentq

#: the example specimen (clamped-free) with a setup: a non-rigid clamp, an accelerometer at
#: the free end and a shaker near the clamp whose moving mass is in the model
SETUP = Setup(
    name="bench",
    masses=(PointMass("acc", 0.34, 0.012),),
    shaker=Shaker(
        0.08,
        gauge_mass=0.004,
        moving_mass=0.05,
        stinger_stiffness=2e5,
        suspension_stiffness=2e3,
        force_at="armature",
    ),
    clamp=Clamp(translational=5e8, rotational=3e4),
)
SPEC = preset("example").replace(n_points=12, setup=SETUP, excitation=preset("example").excitation)


def _fd(specimen, name, modes, positions, h=1e-3):
    """Central differences of the frequencies, shapes at ``positions`` and modal constants
    by ln p (re-solving the eigenproblem; modes followed by MAC)."""
    p0 = next(u for u in updatable(specimen) if u.name == name).nominal
    ref = modal_state(specimen)
    out = []
    for sgn in (1, -1):
        s = with_parameters(specimen, {name: p0 * math.exp(sgn * h)})
        st = modal_state(s)
        pairs = pair_modes(st, ref, modes)
        from iwan_element.models.reduced import axis_rows

        R = axis_rows(s, positions)
        vals = []
        for r, k in pairs.items():
            phi = st.phi[:, k] * np.sign(ref.phi[:, ref.index(r)] @ st.M @ st.phi[:, k])
            vals.append(np.concatenate([[st.frequency(k)], R @ phi, [(st.S @ phi) * (st.E @ phi)]]))
        out.append(np.array(vals))
    return (out[0] - out[1]) / (2 * h)


@pytest.mark.parametrize(
    "name",
    [
        "youngs_modulus",
        "density",
        "clamp.rotational",
        "clamp.translational",
        "mass:acc",
        "shaker.moving_mass",
        "shaker.stinger_stiffness",
        "shaker.position",
        "stiffness_per_area",
        "normal_stiffness_per_area",
    ],
)
def test_sensitivities_equal_finite_differences_of_the_whole_solution(name):
    modes, positions = (1, 2, 3), [0.1, 0.25, 0.34]
    u = next(u for u in updatable(SPEC) if u.name == name)
    st = modal_state(SPEC)
    sens = modal_sensitivities(
        SPEC, {r: st.index(r) for r in modes}, [u], positions=positions, state=st
    )
    fd = _fd(SPEC, name, modes, positions)
    for i, r in enumerate(modes):
        an = np.concatenate([sens["df"][r], sens["dshape"][r][:, 0], sens["dc"][r]])
        scale = np.abs(np.concatenate([[sens["f"][r]], sens["shape"][r], [sens["c"][r]]]))
        # relative to each quantity's own size; the derivative itself must not be negligible
        np.testing.assert_allclose(an / scale, fd[i] / scale, atol=2e-6, rtol=2e-4)
    assert np.max(np.abs(sens["df"][1] / sens["f"][1])) > 1e-6


def test_the_drive_point_moves_the_excitation_row_and_the_modal_constant():
    """A force-measured shaker (force_at="gauge") is the drive point: ``shaker.position``
    moves the gauge mass and the excitation row, so the modal constant's derivative holds
    ``dE phi``; checked against finite differences of the re-solved modes (the sensor
    stays). A passive shaker moves alone (the hammer's excitation stays)."""
    x0 = 0.306  # on beam B, 44 mm from its free end, inside an element
    base = preset("example").replace(n_points=12, excitation=Excitation("shaker", x0))
    spec = base.replace(setup=Setup(shaker=Shaker(x0, gauge_mass=0.004, force_at="gauge")))
    moved = with_parameters(spec, {"shaker.position": x0 - 0.01})
    assert moved.excitation.position == pytest.approx(x0 - 0.01)
    assert moved.sensor_position == spec.sensor_position
    passive = base.replace(setup=Setup(shaker=Shaker(x0, moving_mass=0.05, force_at="passive")))
    assert with_parameters(passive, {"shaker.position": x0 - 0.01}).excitation.position == x0
    u = next(u for u in updatable(spec) if u.name == "shaker.position")
    assert (u.lower, u.upper) == pytest.approx((x0 - 0.005, x0 + 0.005))
    modes = (1, 2, 3)
    st = modal_state(spec)
    sens = modal_sensitivities(spec, {r: st.index(r) for r in modes}, [u], state=st)
    fd = _fd(spec, "shaker.position", modes, [0.3], h=1e-4)
    for i, r in enumerate(modes):
        assert sens["dc"][r][0] == pytest.approx(fd[i][-1], rel=1e-4, abs=1e-6 * abs(sens["c"][r]))
        assert sens["df"][r][0] == pytest.approx(fd[i][0], rel=1e-4, abs=1e-7 * sens["f"][r])
    # not negligible: mode 1's modal constant moves by 0.46 % per mm there
    assert abs(sens["dc"][1][0] / x0 * 1e-3 / sens["c"][1]) > 0.003


def test_a_point_mass_is_the_closed_form_tip_mass_cantilever():
    """attach_setup on a uniform Euler-Bernoulli cantilever's LinearSystem (made here from
    the elements): a tip mass m gives the roots of
    1 + cos(bL) cosh(bL) + (m/(rho A L)) bL (cos(bL) sinh(bL) - sin(bL) cosh(bL)) = 0."""
    L, b, h, E, rho, n = 0.5, 0.02, 0.01, 2e11, 7800.0, 80
    A, I = b * h, b * h**3 / 12
    K, M = np.zeros((3 * (n + 1),) * 2), np.zeros((3 * (n + 1),) * 2)
    for e in range(n):
        ke, me = element_matrices(
            L / n, E=E, G=E / 2.6, kappa=5 / 6, rho=rho, area=A, inertia=I, timoshenko=False
        )
        K[3 * e : 3 * e + 6, 3 * e : 3 * e + 6] += ke
        M[3 * e : 3 * e + 6, 3 * e : 3 * e + 6] += me
    free = np.arange(3, 3 * (n + 1))
    ix = np.ix_(free, free)
    Ls = LinearSystem(
        M=M[ix],
        K0=K[ix],
        Kb=K[ix],
        G=np.zeros((0, free.size)),
        S=np.zeros(free.size),
        free=free,
        n_coordinates=3 * (n + 1),
        E=np.zeros(free.size),
    )

    def rows(x):  # the free end only
        U, W, T = (np.zeros((1, free.size)) for _ in range(3))
        U[0, -3], W[0, -2], T[0, -1] = 1, 1, 1
        return U, W, T

    ratio = 0.3
    La = attach_setup(Ls, Setup(masses=(PointMass("tip", L, ratio * rho * A * L),)), rows)
    w2 = eigh(La.K0, La.M, eigvals_only=True)
    f_fe = np.sort(np.sqrt(w2))[:3] / (2 * np.pi)

    def g(bl):
        return (
            1
            + math.cos(bl) * math.cosh(bl)
            + ratio * bl * (math.cos(bl) * math.sinh(bl) - math.sin(bl) * math.cosh(bl))
        )

    grid = np.linspace(0.5, 12, 2000)
    roots = [brentq(g, a, c) for a, c in zip(grid[:-1], grid[1:]) if g(a) * g(c) < 0][:3]
    f_ref = np.array(roots) ** 2 / (2 * np.pi * L**2) * math.sqrt(E * I / (rho * A))
    # transverse modes only (the axial ones are kHz higher and carry the mass too)
    np.testing.assert_allclose(f_fe[:2], f_ref[:2], rtol=1e-5)


def test_the_shakers_moving_mass_limits():
    """A very stiff stinger makes the moving mass a point mass at the drive point; a very
    soft one (no suspension) leaves the beam's elastic modes unchanged and adds a mode near
    0 Hz; force_at="gauge" adds the gauge mass only (the rest is behind the measured
    force)."""
    base = preset("example").replace(n_points=12)
    bare = natural_frequencies(base, n_modes=3)
    point = natural_frequencies(
        base.replace(setup=Setup(masses=(PointMass("m", 0.08, 0.05),))), n_modes=3
    )
    stiff = natural_frequencies(
        base.replace(
            setup=Setup(
                shaker=Shaker(0.08, moving_mass=0.05, stinger_stiffness=1e12, force_at="armature")
            )
        ),
        n_modes=3,
    )
    soft = natural_frequencies(
        base.replace(
            setup=Setup(
                shaker=Shaker(0.08, moving_mass=0.05, stinger_stiffness=1e-3, force_at="armature")
            )
        ),
        n_modes=4,
    )
    np.testing.assert_allclose(stiff, point, rtol=1e-5)
    assert soft[0] < 1.0
    np.testing.assert_allclose(soft[1:], bare, rtol=1e-6)
    gauge = natural_frequencies(
        base.replace(
            setup=Setup(
                shaker=Shaker(0.08, gauge_mass=0.05, moving_mass=0.5, stinger_stiffness=1e5)
            )
        ),
        n_modes=3,
    )
    np.testing.assert_allclose(gauge, point, rtol=1e-9)


def _targets(truth, modes, positions):
    st = modal_state(truth)
    from iwan_element.models.reduced import axis_rows

    R = axis_rows(truth, positions)
    freqs = {r: st.frequency(st.index(r)) for r in modes}
    shapes = {r: dict(zip(positions, R @ st.phi[:, st.index(r)])) for r in modes}
    return freqs, shapes


def test_update_recovers_a_known_truth_and_leaves_what_it_cannot_see():
    """Wrong E, clamp stiffness and sensor mass: updated from the truth's own frequencies
    and shapes back to the truth within stderr; the shaker's moving mass, behind the
    measured force (force_at="gauge"), is invisible: named in a warning, left nominal."""
    spec = SPEC.replace(
        setup=Setup(
            masses=SETUP.masses,
            clamp=SETUP.clamp,
            shaker=Shaker(0.08, gauge_mass=0.004, moving_mass=0.05, force_at="gauge"),
        )
    )
    truth = with_parameters(
        spec,
        {
            "youngs_modulus": spec.youngs_modulus * 1.04,
            "clamp.rotational": 1.5e4,
            "mass:acc": 0.035,
        },
    )
    freqs, shapes = _targets(truth, (1, 2, 3, 4), [0.05, 0.15, 0.25, 0.3, 0.34])
    r = linear_update(
        spec,
        frequencies=freqs,
        shapes=shapes,
        parameters=("youngs_modulus", "clamp.rotational", "mass:acc", "shaker.moving_mass"),
    )
    want = {"youngs_modulus": truth.youngs_modulus, "clamp.rotational": 1.5e4, "mass:acc": 0.035}
    for n, v in want.items():
        p = r.params[n]
        assert p.identified and abs(p.value - v) < 2 * p.stderr, (n, p, v)
        assert abs(r.nominal[n] - v) > 3 * p.stderr  # the nominal was clearly off
    mm = r.params["shaker.moving_mass"]
    assert not mm.identified and mm.value == 0.05
    assert any("shaker.moving_mass" in w and "cannot see" in w for w in r.warnings)
    assert not r.success and "shaker.moving_mass" in r.verdict()
    assert r.specimen.setup.shaker.moving_mass == 0.05
    assert r.specimen.youngs_modulus == pytest.approx(r.params["youngs_modulus"].value)
    # after the update the targets are met far better than before
    before = np.array([row["residual_before"] for row in r.residuals])
    after = np.array([row["residual_after"] for row in r.residuals])
    assert np.sqrt(np.mean(after**2)) < 0.2 * np.sqrt(np.mean(before**2))
    # a mode that was no target: predicted within its stated band
    st = modal_state(truth)
    f5, se5 = r.predict(5)
    assert abs(f5 - st.frequency(st.index(5))) < 2 * se5
    assert r.to_dict()["params"] and "Linear update" in r.report()


def test_bad_input_is_refused_naming_the_argument():
    s = preset("example")
    with pytest.raises(ValueError, match="parameters"):
        linear_update(s, frequencies={1: 60.0}, parameters=("clamp.rotational",))
    with pytest.raises(ValueError, match="frequencies"):
        linear_update(s, frequencies={1: -5.0}, parameters="material")
    with pytest.raises(ValueError, match="mode"):
        linear_update(s, frequencies={500: 60.0}, parameters="material")
    with pytest.raises(ValueError, match="model_error"):
        linear_update(
            s, frequencies={1: 60.0}, parameters="material", model_error={"frequency": -1}
        )
    with pytest.raises(ValueError, match="setup"):
        s.replace(setup=Setup(masses=(PointMass("far", 5.0, 0.01),)))
    with pytest.raises(ValueError, match="clamp"):
        preset("brake-reuss").replace(setup=Setup(clamp=Clamp(1e6, 1e3)))
