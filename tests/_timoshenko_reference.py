"""Exact natural frequencies of a uniform Timoshenko beam (test reference only).

Written from the beam equations, independently of any finite-element model in the package, so
that a Timoshenko beam discretisation can be checked against it. Han, Benaroya and Wei
("Dynamics of transversely vibrating beams using four engineering theories", J. Sound Vib.
225:935-988, 1999) give the equations and boundary conditions used here:

    EI psi'' + kappa G A (w' - psi) - rho I psi_tt = 0          (moment balance)
    kappa G A (w'' - psi') - rho A w_tt = 0                     (force balance)

with the deflection ``w`` [m], the cross-section rotation ``psi`` [rad], the bending moment
``M = EI psi'`` and the shear force ``Q = kappa G A (w' - psi) = -EI psi'' - rho I omega^2 psi``
(the second form holds for harmonic motion and stays finite when shear is switched off).

Dimensionless form. With ``x = L (1/2 + xi)``, ``xi`` in [-1/2, 1/2], the frequency parameter
``Omega^2 = rho A L^4 omega^2 / (E I)`` (``Omega = (beta L)^2`` for an Euler-Bernoulli beam), the
rotary-inertia parameter ``b = I / (A L^2)`` and the shear-flexibility parameter
``a = E I / (kappa G A L^2)``, a solution ``w ~ exp(s x)`` has ``Lambda = (s L)^2`` a root of

    (Lambda + a Omega^2) (Lambda + b Omega^2) = Omega^2,

two real roots ``Lambda_1 > Lambda_2`` for every ``Omega > 0`` (the discriminant is
``((a - b) Omega^2 / 2)^2 + Omega^2 > 0``). ``Lambda_2 < 0`` always; ``Lambda_1 > 0`` below the
cut-off ``Omega_c^2 = 1 / (a b)``, i.e. ``omega_c = sqrt(kappa G A / (rho I))``, and ``< 0``
above it. Setting ``a = 0`` gives the Rayleigh beam, ``b = 0`` the shear beam and
``a = b = 0`` the Euler-Bernoulli beam; the same equations hold in all four theories.

Basis. For each root ``Lambda`` the even and odd (about mid-span) solutions are built from
``C = cosh(sqrt(Lambda) xi)`` and ``S = sinh(sqrt(Lambda) xi) / sqrt(Lambda)``, which are entire
functions of ``Lambda`` (cos and sin / sqrt(-Lambda) for ``Lambda < 0``, ``1`` and ``xi`` at
``Lambda = 0``). Below and above the cut-off the same formulae therefore apply, and the
boundary matrix is continuous across ``omega_c``: both branches, and the frequencies above
the cut-off (the "second spectrum"), are handled, not ignored. Growing hyperbolic terms are
divided by ``cosh(sqrt(Lambda) / 2)``, and each column and row of the 4 x 4 boundary matrix is
scaled to unit largest entry: positive continuous factors that leave the sign changes of the
determinant at the eigenvalues only. Roots are bracketed on a grid of 200 points per ``pi``
of the oscillating phase ``sqrt(-Lambda_2) + sqrt(max(-Lambda_1, 0))`` and refined with
:func:`scipy.optimize.brentq`; two eigenvalues closer than about 1/200 of the local spacing
would cancel and be missed (the symmetric and antisymmetric modes of a symmetric beam are not
separated). The search stops at the Euler-Bernoulli frequency of the same mode number times
1.1 (with ``(n + 1) pi`` in place of ``beta_n L``), an upper bound: shear flexibility and rotary
inertia only lower eigenvalues (min-max principle).
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

BOUNDARY_CONDITIONS = ("pinned-pinned", "free-free", "clamped-free", "clamped-clamped")

#: rows of the end quantity vector [w / L, psi, psi' L, Q L^2 / (E I)] fixed by each end type
_END_ROWS = {"clamped": (0, 1), "pinned": (0, 2), "free": (2, 3)}
_POINTS_PER_PI = 200


def _check_inputs(E, G, kappa, rho, A, I, L, bc, n_modes):
    for name, value in (
        ("E", E),
        ("G", G),
        ("kappa", kappa),
        ("rho", rho),
        ("A", A),
        ("I", I),
        ("L", L),
    ):
        if not (np.isfinite(value) and value > 0):
            raise ValueError(f"{name} must be a finite number > 0, got {value!r}")
    if bc not in BOUNDARY_CONDITIONS:
        raise ValueError(f"bc must be one of {BOUNDARY_CONDITIONS}, got {bc!r}")
    if int(n_modes) != n_modes or n_modes < 1:
        raise ValueError(f"n_modes must be an integer >= 1, got {n_modes!r}")


def beam_parameters(*, E, G, kappa, rho, A, I, L, shear=True, rotary_inertia=True):
    """Dimensionless parameters of a uniform Timoshenko beam.

    Parameters
    ----------
    E, G : float
        Young's and shear modulus [Pa].
    kappa : float
        Shear coefficient [-] (5/6 for a rectangle).
    rho : float
        Density [kg/m^3].
    A, I : float
        Cross-section area [m^2] and second moment of area about the bending axis [m^4].
    L : float
        Length [m].
    shear, rotary_inertia : bool
        Keep shear flexibility / rotary inertia (switching one off gives the Rayleigh or the
        shear beam, both off the Euler-Bernoulli beam).

    Returns
    -------
    a, b, omega_unit : float
        Shear flexibility ``E I / (kappa G A L^2)`` [-], rotary inertia ``I / (A L^2)`` [-], and
        ``sqrt(E I / (rho A L^4))`` [rad/s], with ``omega = Omega * omega_unit``.
    """
    a = E * I / (kappa * G * A * L**2) if shear else 0.0
    b = I / (A * L**2) if rotary_inertia else 0.0
    return a, b, np.sqrt(E * I / (rho * A * L**4))


def cutoff_frequency(*, G, kappa, rho, A, I):
    """Cut-off frequency ``sqrt(kappa G A / (rho I)) / (2 pi)`` [Hz] of the Timoshenko beam.

    Above it both wavenumbers are oscillatory (the "second spectrum" of Timoshenko theory).
    Units as in :func:`beam_parameters`.
    """
    return np.sqrt(kappa * G * A / (rho * I)) / (2.0 * np.pi)


def wavenumber_roots(Omega, a, b):
    """Roots ``Lambda_1 > Lambda_2`` of ``(Lambda + a Omega^2)(Lambda + b Omega^2) = Omega^2``.

    Parameters
    ----------
    Omega : array_like
        Frequency parameter ``sqrt(rho A L^4 / (E I)) omega`` [-], > 0.
    a, b : float
        Shear-flexibility and rotary-inertia parameters (:func:`beam_parameters`).

    Returns
    -------
    Lambda_1, Lambda_2 : ndarray
        ``(s L)^2`` of the two solution pairs ``exp(+-s x)`` [-]. ``Lambda_1`` is computed from
        the product of the roots, free of cancellation, and changes sign at the cut-off.
    """
    W2 = np.asarray(Omega, float) ** 2
    root = np.sqrt((0.5 * (a - b) * W2) ** 2 + W2)
    lam2 = -0.5 * (a + b) * W2 - root
    lam1 = (W2 - a * b * W2**2) / (0.5 * (a + b) * W2 + root)
    return lam1, lam2


def _end_values(lam):
    """Scaled ``C(1/2)`` and ``S(1/2)`` for roots ``lam`` (each column's positive factor
    ``1 / cosh(sqrt(lam) / 2)`` applied when ``lam > 0``)."""
    z = np.sqrt(np.abs(lam))
    pos = lam > 0
    with np.errstate(invalid="ignore", divide="ignore"):
        s_hyp = np.where(z > 0, np.tanh(0.5 * z) / np.where(z > 0, z, 1.0), 0.5)
    C = np.where(pos, 1.0, np.cos(0.5 * z))
    S = np.where(pos, s_hyp, 0.5 * np.sinc(z / (2.0 * np.pi)))
    return C, S


def _column_quantities(lam, Omega, a, b, sign):
    """End quantities [w / L, psi, psi' L, Q L^2 / (E I)] at ``xi = sign / 2`` of the even
    (``w = C``, ``psi = (lam + a Omega^2) S``) and the odd (``psi = C``,
    ``w / L = (1 - a (lam + b Omega^2)) S``) solution; shape (..., 4, 2)."""
    C, S = _end_values(lam)
    W2 = Omega**2
    g = lam + a * W2  # psi / w' factor of the even solution
    h = lam + b * W2
    even = np.stack([C, sign * g * S, g * C, -sign * g * h * S], axis=-1)
    odd = np.stack([sign * (1.0 - a * h) * S, C, sign * lam * S, -h * C], axis=-1)
    return np.stack([even, odd], axis=-1)


def boundary_matrix(Omega, a, b, bc):
    """The 4 x 4 boundary matrix (rows: two conditions at each end; columns: even and odd
    solutions of ``Lambda_1`` then ``Lambda_2``), columns and rows scaled to unit largest
    entry. ``Omega``: array of frequency parameters [-] > 0; returns shape (len(Omega), 4, 4)."""
    Omega = np.atleast_1d(np.asarray(Omega, float))
    left, right = bc.split("-")
    lam1, lam2 = wavenumber_roots(Omega, a, b)
    blocks = []
    for end, sign in ((left, -1.0), (right, 1.0)):
        q = np.concatenate(
            [
                _column_quantities(lam1, Omega, a, b, sign),
                _column_quantities(lam2, Omega, a, b, sign),
            ],
            axis=-1,
        )
        blocks.append(q[:, list(_END_ROWS[end]), :])
    mat = np.concatenate(blocks, axis=1)
    col = np.max(np.abs(mat), axis=1, keepdims=True)
    mat = mat / np.where(col > 0, col, 1.0)
    row = np.max(np.abs(mat), axis=2, keepdims=True)
    return mat / np.where(row > 0, row, 1.0)


def frequency_determinant(Omega, a, b, bc):
    """Scaled determinant of :func:`boundary_matrix`; zero (with a sign change) at each
    natural frequency parameter ``Omega`` [-]."""
    return np.linalg.det(boundary_matrix(Omega, a, b, bc))


def _search_grid(Omega_max, a, b):
    """Frequency parameters from near 0 to ``Omega_max``, 200 per ``pi`` of phase."""
    pre = np.linspace(0.0, np.sqrt(Omega_max), 20001)[1:] ** 2
    lam1, lam2 = wavenumber_roots(pre, a, b)
    phase = np.sqrt(-lam2) + np.sqrt(np.maximum(-lam1, 0.0))
    phase = np.maximum.accumulate(phase)
    n = int(np.ceil(phase[-1] * _POINTS_PER_PI / np.pi)) + 1
    targets = np.linspace(0.02 * np.pi, phase[-1], max(n, 2))
    keep = np.concatenate([[True], np.diff(phase) > 0])
    return np.unique(np.interp(targets, phase[keep], pre[keep]))


def determinant_roots(a, b, bc, n_modes):
    """First ``n_modes`` natural frequency parameters ``Omega`` [-] from sign changes of
    :func:`frequency_determinant` followed by Brent's method (rigid-body modes, at
    ``Omega = 0``, are not roots on the grid, which starts above zero)."""
    Omega_max = 1.1 * ((n_modes + 1) * np.pi) ** 2
    grid = _search_grid(Omega_max, a, b)
    det = np.empty_like(grid)
    change = np.empty(0, dtype=int)
    for start in range(0, len(grid), 2000):  # stop once n_modes brackets are found
        stop = min(start + 2001, len(grid))
        det[start:stop] = frequency_determinant(grid[start:stop], a, b, bc)
        sign = np.sign(det[:stop])
        change = np.flatnonzero((sign[:-1] * sign[1:] < 0) | (sign[1:] == 0))
        if len(change) >= n_modes:
            break
    if len(change) < n_modes:
        raise RuntimeError(
            f"found {len(change)} roots below the Euler-Bernoulli bound "
            f"Omega = {Omega_max:.4g}, expected at least {n_modes}"
        )

    def scalar(W):
        return frequency_determinant(W, a, b, bc)[0]

    roots = []
    for i in change[:n_modes]:
        lo, hi = grid[i], grid[i + 1]
        roots.append(
            hi
            if det[i + 1] == 0
            else brentq(scalar, lo, hi, xtol=1e-15 * hi, rtol=4 * np.finfo(float).eps)
        )
    return np.array(roots)


def pinned_roots(a, b, n_modes):
    """First ``n_modes`` frequency parameters ``Omega`` [-] of the pinned-pinned beam in
    closed form: for ``w = sin(n pi x / L)`` the frequency equation is the quadratic
    ``a b Omega^4 - (1 + (a + b) k^2) Omega^2 + k^4 = 0`` in ``Omega^2``, ``k = n pi``.
    Both roots are kept (the upper one lies above the cut-off), and ``k = 0`` contributes
    the cut-off itself, ``Omega^2 = 1 / (a b)`` (``w = 0``, uniform shear rotation ``psi``,
    which satisfies ``w = 0`` and ``psi' = 0`` at both ends)."""
    k2 = (np.arange(1, n_modes + 1) * np.pi) ** 2
    p = 1.0 + (a + b) * k2
    disc = np.sqrt((a - b) ** 2 * k2**2 + 2.0 * (a + b) * k2 + 1.0)  # sqrt(p^2 - 4 a b k^4)
    lower = np.sqrt(2.0 * k2**2 / (p + disc))
    roots = [lower]
    if a * b > 0:
        roots += [np.sqrt((p + disc) / (2.0 * a * b)), [1.0 / np.sqrt(a * b)]]
    return np.sort(np.concatenate(roots))[:n_modes]


def timoshenko_frequencies(
    *, E, G, kappa, rho, A, I, L, bc, n_modes, shear=True, rotary_inertia=True, method="auto"
):
    """Natural frequencies of a uniform Timoshenko beam from the exact frequency equation.

    Parameters
    ----------
    E, G : float
        Young's and shear modulus [Pa].
    kappa : float
        Shear coefficient [-] (5/6 for a rectangle).
    rho : float
        Density [kg/m^3].
    A, I : float
        Cross-section area [m^2] and second moment of area about the bending axis [m^4].
    L : float
        Length [m].
    bc : {"pinned-pinned", "free-free", "clamped-free", "clamped-clamped"}
        End conditions (left-right; "clamped-free" is a cantilever).
    n_modes : int
        Number of frequencies returned.
    shear, rotary_inertia : bool
        Keep shear flexibility / rotary inertia; switching one or both off gives the Rayleigh,
        shear or Euler-Bernoulli beam (Han, Benaroya and Wei 1999).
    method : {"auto", "determinant", "closed-form"}
        "closed-form" (pinned-pinned only) solves the quadratic of each wave number
        ``n pi / L``; "determinant" finds roots of the 4 x 4 boundary determinant; "auto"
        takes the closed form for pinned-pinned and the determinant otherwise.

    Returns
    -------
    ndarray
        The lowest ``n_modes`` natural frequencies [Hz], ascending, frequencies above the
        cut-off :func:`cutoff_frequency` included; rigid-body modes (free-free: translation
        and rotation at 0 Hz) excluded.
    """
    _check_inputs(E, G, kappa, rho, A, I, L, bc, n_modes)
    if method not in ("auto", "determinant", "closed-form"):
        raise ValueError(f"method must be 'auto', 'determinant' or 'closed-form', got {method!r}")
    if method == "closed-form" and bc != "pinned-pinned":
        raise ValueError(f"method='closed-form' needs bc='pinned-pinned', got {bc!r}")
    a, b, omega_unit = beam_parameters(
        E=E, G=G, kappa=kappa, rho=rho, A=A, I=I, L=L, shear=shear, rotary_inertia=rotary_inertia
    )
    closed = method == "closed-form" or (method == "auto" and bc == "pinned-pinned")
    Omega = pinned_roots(a, b, n_modes) if closed else determinant_roots(a, b, bc, n_modes)
    return Omega * omega_unit / (2.0 * np.pi)
