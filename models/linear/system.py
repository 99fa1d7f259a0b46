"""The linear system every analysis of a specimen reads, and the test setup built into it.

:class:`LinearSystem` holds a specimen's mass and stiffness on its free coordinates with the
rows that read the contact points' slips and gaps, the sensor and the excitation: the 1-D
Timoshenko beams (:func:`~iwan_element.models.reduced.dispatch.linear_system`) and the reduced solid
bodies (:meth:`~iwan_element.models.solid.SolidSpecimen.linear_system`) give the same type.
:func:`attach_setup` adds a :class:`~iwan_element.models.specimens.setups.Setup` to it, the same way
for both hosts: point masses through the rows of their positions, a shaker's gauge mass at
the drive point and, when its moving mass is in the model, one more coordinate (the moving
mass) on the stinger and the suspension (:mod:`~iwan_element.models.specimens.setups`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..specimens.setups import Setup

__all__ = ["LinearSystem", "attach_setup"]


@dataclass(frozen=True)
class LinearSystem:
    """Linear matrices of a specimen on its free coordinates.

    ``K0`` holds the bodies, the normal contact springs and the setup's springs (clamp,
    stinger, suspension) but no tangential interface stiffness; ``Kb`` the bodies alone
    (their strain energy is ``x^T Kb x / 2``; ``K0 - Kb`` is the springs'). ``G`` maps
    coordinates to the tangential slips of the contact points, ``S`` to the sensor's
    transverse displacement and ``E`` to the excitation's generalised displacement (the
    force vector of a unit excitation force is ``E``, by reciprocity: the drive point's
    transverse displacement, or a shaker's moving mass when the force drives it). ``Gn``
    maps to the normal gaps (``None`` where not kept); ``drive`` is the row of a prescribed
    coordinate (the machine grip of a ``"clamped-driven"`` specimen), else ``None``.
    ``free`` are the indices of the kept coordinates among ``n_coordinates`` of the host
    model. ``rigid_body_modes``: zero-frequency modes (3 for a free-free planar specimen,
    6 for a free-free solid, 0 when clamped). ``n_extra``: coordinates the setup added
    (last; the moving mass of a shaker), which the bodies' rows do not read.
    """

    M: np.ndarray
    K0: np.ndarray
    Kb: np.ndarray
    G: np.ndarray
    S: np.ndarray
    free: np.ndarray
    n_coordinates: int
    rigid_body_modes: int = 0
    E: np.ndarray | None = None
    Gn: np.ndarray | None = None
    drive: np.ndarray | None = None
    n_extra: int = 0


def _pad(A, n):
    """``A`` (vector or rows) with ``n`` zero columns appended."""
    A = np.asarray(A, float)
    if n == 0:
        return A
    return np.concatenate([A, np.zeros(A.shape[:-1] + (n,))], axis=-1)


def attach_setup(L: LinearSystem, setup: Setup, rows) -> LinearSystem:
    """``L`` with the setup's masses and shaker built in (module docstring).

    Parameters
    ----------
    L : LinearSystem
        The bare system (no setup).
    setup : Setup
        Its ``clamp`` is the host's business (the beams' root coordinates) and is not read
        here.
    rows : callable
        ``rows(positions) -> (U, W, Theta)``: the axial and transverse displacement and the
        rotation at ``positions`` [m] on the axis, each ``(len(positions), n)`` over ``L``'s
        coordinates; ``U`` and ``Theta`` may be ``None`` (the solid bodies: transverse only).

    Returns
    -------
    LinearSystem
        With ``n_extra = 1`` and the excitation row on the moving mass when a shaker's
        armature is in the model and the force drives it (``force_at="armature"``).
    """
    if setup.empty or (not setup.masses and setup.shaker is None):
        return L
    M, K0 = np.array(L.M, float), np.array(L.K0, float)
    items = [(m.position, m.mass, m.rotary_inertia) for m in setup.masses]
    sh = setup.shaker
    if sh is not None and sh.gauge_mass > 0:
        items.append((sh.position, sh.gauge_mass, 0.0))
    if items:
        U, W, T = rows([p for p, _, _ in items])
        for k, (_, m, J) in enumerate(items):
            M += m * np.outer(W[k], W[k])
            if U is not None:
                M += m * np.outer(U[k], U[k])
            if T is not None and J > 0:
                M += J * np.outer(T[k], T[k])
    if sh is None or not sh.armature:
        return replace(L, M=0.5 * (M + M.T), K0=0.5 * (K0 + K0.T))
    n = M.shape[0]
    w_d = rows([sh.position])[1][0]
    M, K0 = _pad(np.vstack([M, np.zeros((1, n))]), 1), _pad(np.vstack([K0, np.zeros((1, n))]), 1)
    M[n, n] = sh.moving_mass
    link = np.append(w_d, -1.0)  # stinger: drive point minus moving mass
    K0 += sh.stinger_stiffness * np.outer(link, link)
    K0[n, n] += sh.suspension_stiffness
    E = _pad(L.E, 1) if L.E is not None else None
    if sh.force_at == "armature":
        E = np.zeros(n + 1)
        E[n] = 1.0
    return replace(
        L,
        M=M,
        K0=0.5 * (K0 + K0.T),
        Kb=_pad(np.vstack([L.Kb, np.zeros((1, n))]), 1),
        G=_pad(L.G, 1),
        S=_pad(L.S, 1),
        E=E,
        Gn=None if L.Gn is None else _pad(L.Gn, 1),
        drive=None if L.drive is None else _pad(L.drive, 1),
        free=np.append(L.free, L.n_coordinates),
        n_coordinates=L.n_coordinates + 1,
        n_extra=L.n_extra + 1,
    )
