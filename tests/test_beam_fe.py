"""The 1-D Timoshenko beam elements (models/beam/elements.py) against the closed-form Timoshenko
beam (tests/_timoshenko_reference.py, written independently from the exact frequency
equations) and the element's own published closed-form stiffness."""

import numpy as np
import pytest
from _timoshenko_reference import timoshenko_frequencies
from iwan_element.models import natural_frequencies, preset
from iwan_element.models.beam import element_matrices, point_rows
from scipy.linalg import eigh

E, NU, RHO, KAPPA = 192.31e9, 0.3, 8000.0, 5.0 / 6.0
G = E / (2 * (1 + NU))


def _section(b, h):
    return b * h, b * h**3 / 12


def test_element_stiffness_is_friedman_and_kosmatkas_closed_form():
    """Friedman & Kosmatka (1993), eq. for the two-node element:
    K = EI / (l^3 (1 + Phi)) [[12, 6l, -12, 6l], [6l, (4 + Phi) l^2, -6l, (2 - Phi) l^2], ...]."""
    A, I = _section(0.0254, 0.0127)
    for l in (0.002, 0.03, 0.4):
        K, _ = element_matrices(l, E=E, G=G, kappa=KAPPA, rho=RHO, area=A, inertia=I)
        phi = 12 * E * I / (KAPPA * G * A * l * l)
        ref = (
            E
            * I
            / (l**3 * (1 + phi))
            * np.array(
                [
                    [12, 6 * l, -12, 6 * l],
                    [6 * l, (4 + phi) * l * l, -6 * l, (2 - phi) * l * l],
                    [-12, -6 * l, 12, -6 * l],
                    [6 * l, (2 - phi) * l * l, -6 * l, (4 + phi) * l * l],
                ]
            )
        )
        ib = [1, 2, 4, 5]
        np.testing.assert_allclose(
            K[np.ix_(ib, ib)], ref, rtol=1e-10, atol=1e-9 * np.abs(ref).max()
        )
        np.testing.assert_allclose(
            K[np.ix_([0, 3], [0, 3])], E * A / l * np.array([[1, -1], [-1, 1]]), rtol=1e-12
        )


def _uniform_beam(L, b, h, n, *, timoshenko=True):
    A, I = _section(b, h)
    K, M = np.zeros((3 * (n + 1),) * 2), np.zeros((3 * (n + 1),) * 2)
    for e in range(n):
        ke, me = element_matrices(
            L / n, E=E, G=G, kappa=KAPPA, rho=RHO, area=A, inertia=I, timoshenko=timoshenko
        )
        K[3 * e : 3 * e + 6, 3 * e : 3 * e + 6] += ke
        M[3 * e : 3 * e + 6, 3 * e : 3 * e + 6] += me
    return K, M, A, I


def _bending_frequencies(K, M, keep, n_modes, skip):
    """Transverse-dominated eigenfrequencies [Hz] (axial modes removed by holding u)."""
    w2 = eigh(K[np.ix_(keep, keep)], M[np.ix_(keep, keep)], eigvals_only=True)
    return np.sqrt(np.abs(w2[skip : skip + n_modes])) / (2 * np.pi)


@pytest.mark.parametrize("bc", ["free-free", "clamped-free", "pinned-pinned"])
@pytest.mark.parametrize("h", [0.0127, 0.06])  # slender and thick (L/r = 196, 42)
def test_timoshenko_elements_converge_to_the_exact_beam(bc, h):
    """Within 2e-4 for the first four modes (the element's shear strain is constant, so
    its frequencies converge as h^2: 4e-4 at 60 elements for the thick beam's 4th mode)."""
    L, b = 0.72, 0.0254
    n = 60 if h < 0.02 else 120
    K, M, A, I = _uniform_beam(L, b, h, n)
    dofs = np.arange(3 * (n + 1)).reshape(-1, 3)
    held = set(dofs[:, 0])  # no axial motion: bending only
    if bc == "clamped-free":
        held |= {1, 2}
    if bc == "pinned-pinned":
        held |= {1, dofs[-1, 1]}
    keep = np.array(sorted(set(range(K.shape[0])) - held))
    skip = 2 if bc == "free-free" else 0
    fe = _bending_frequencies(K, M, keep, 4, skip)
    ref = timoshenko_frequencies(E=E, G=G, kappa=KAPPA, rho=RHO, A=A, I=I, L=L, bc=bc, n_modes=4)
    np.testing.assert_allclose(fe, ref, rtol=2e-4)
    eb = timoshenko_frequencies(
        E=E,
        G=G,
        kappa=KAPPA,
        rho=RHO,
        A=A,
        I=I,
        L=L,
        bc=bc,
        n_modes=4,
        shear=False,
        rotary_inertia=False,
    )
    assert np.all(ref < eb) and np.max(1 - ref / eb) > 5e-3  # the effect tested is not small
    K, M, *_ = _uniform_beam(L, b, h, n, timoshenko=False)
    np.testing.assert_allclose(_bending_frequencies(K, M, keep, 4, skip), eb, rtol=1e-4)


def test_point_rows_interpolate_the_element_shapes():
    """Reading w at a node gives its coordinate; between nodes a rigid rotation of the whole
    specimen (w = c + a x, theta = a, u = 0 on the axis) is read exactly."""
    s = preset("brake-reuss")
    from iwan_element.models.beam import beam_mesh

    mesh = beam_mesh(s)
    x = np.concatenate([mesh.x_a, mesh.x_b])
    q = np.zeros(3 * x.size)
    q[1::3] = 1e-3 + 2e-3 * x
    q[2::3] = 2e-3
    pos = np.linspace(0.0, s.total_length, 37)
    U, W, Th = point_rows(s, pos, mesh)
    np.testing.assert_allclose(W @ q, 1e-3 + 2e-3 * pos, rtol=1e-12)
    np.testing.assert_allclose(Th @ q, 2e-3, rtol=1e-12)
    np.testing.assert_allclose(U @ q, 0.0, atol=1e-18)


def test_shear_and_rotary_inertia_lower_the_specimens_bending_modes():
    """The same specimen with Euler-Bernoulli beams is stiffer in every bending mode (by
    0.4-0.7 % for the Brake-Reuss beam, whose lap halves are 6.35 mm thick)."""
    s = preset("brake-reuss")
    t = natural_frequencies(s, n_modes=6)[3:]
    e = natural_frequencies(s.replace(beam_theory="euler-bernoulli"), n_modes=6)[3:]
    shift = t / e - 1
    assert np.all(shift < -1e-3) and np.all(shift > -2e-2)
