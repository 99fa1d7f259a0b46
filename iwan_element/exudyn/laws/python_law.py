"""The Python force law of the connector: closures calling ``joint.trial`` (the reference
route, and the only one for elements without a symbolic form).
"""

from __future__ import annotations

from collections.abc import Callable

import exudyn as exu

__all__ = ["coordinate_force_function", "position_force_function", "rotating_axis_force_function"]

_ROTATION_MATRIX = exu.OutputVariableType.RotationMatrix


# ---------------------------------------------------------------------------- force functions
# These closures are the hot path: they run at every force evaluation of the solver. They
# read the connector's small state by attribute access and call the bound trial method;
# no numpy and no allocation beyond the return value. The cache ``conn._lF`` holds the
# element's force; the dashpot in parallel (``conn._damping``) is added on return.
def coordinate_force_function(conn) -> Callable[..., float]:
    """The user function giving the force [N] of a coordinate connector (on ``deltaL``)."""
    trial = conn._joint.trial
    off = conn._offset  # fixed at creation (the object's own offset is not read)
    c = conn._damping  # the dashpot in parallel (0.0: none)

    def iwan_coordinate_force(mbs, t, itemNumber, deltaL, deltaL_t, stiffness, damping, offset):
        u = deltaL - off
        if t <= conn._guard:
            conn._check(mbs, t, u)
        if u == conn._lu and deltaL_t == conn._lv:
            return conn._lF + c * deltaL_t
        F = trial(u, deltaL_t)[0]
        conn._lu = u
        conn._lv = deltaL_t
        conn._lF = F
        return F + c * deltaL_t

    return iwan_coordinate_force


def _axial_force(conn, trial, mbs, t, displacement, velocity, a0, a1, a2, off):
    """Force vector of the joint along the unit axis ``(a0, a1, a2)`` (the position routes;
    their elements' trials cost far more than this call).
    """
    u = displacement[0] * a0 + displacement[1] * a1 + displacement[2] * a2 - off
    if t <= conn._guard:
        conn._check(mbs, t, u)
    v = velocity[0] * a0 + velocity[1] * a1 + velocity[2] * a2
    if u == conn._lu and v == conn._lv:
        F = conn._lF
    else:
        F = trial(u, v)[0]
        conn._lu = u
        conn._lv = v
        conn._lF = F
    F += conn._damping * v
    return [F * a0, F * a1, F * a2]


def position_force_function(conn) -> Callable[..., float]:
    """The user function giving the force [N] of a position connector along its fixed axis."""
    trial = conn._joint.trial
    a0, a1, a2 = conn._axis
    off = conn._offset

    def iwan_position_force(mbs, t, itemNumber, displacement, velocity, stiffness, damping, offset):
        return _axial_force(conn, trial, mbs, t, displacement, velocity, a0, a1, a2, off)

    return iwan_position_force


def rotating_axis_force_function(conn) -> Callable[..., list[float]]:
    """The user function giving the force [N] along an axis turning with its marker."""
    trial = conn._joint.trial
    l0, l1, l2 = conn._axis
    off = conn._offset
    marker = conn._axis_marker
    get = conn._mbs.GetMarkerOutput

    def iwan_rotating_axis_force(
        mbs, t, itemNumber, displacement, velocity, stiffness, damping, offset
    ):
        A = get(marker, _ROTATION_MATRIX).tolist()  # row-major 3x3, current configuration
        return _axial_force(
            conn,
            trial,
            mbs,
            t,
            displacement,
            velocity,
            A[0] * l0 + A[1] * l1 + A[2] * l2,
            A[3] * l0 + A[4] * l1 + A[5] * l2,
            A[6] * l0 + A[7] * l1 + A[8] * l2,
            off,
        )

    return iwan_rotating_axis_force
