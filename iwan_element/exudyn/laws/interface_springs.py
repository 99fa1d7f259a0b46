"""Linear springs carried by the interface's own connector objects (``add_iwan_interface``'s
``stiffness``): one Exudyn object per contact point instead of a built-in spring plus a joint.

Measured on the Brake-Reuss ring-down (34 points, Exudyn 1.13.6): 34 extra symbolic
Cartesian connectors with a zero law cost about a third of the whole linear beam model, while
replacing its 34 built-in springs by symbolic ones costs about a tenth; so the normal contact
springs are cheapest inside the joint's object.
"""

from __future__ import annotations

import math

import exudyn as exu
import numpy as np
from exudyn.itemInterface import ObjectConnectorCartesianSpringDamper
from numpy.typing import NDArray

__all__ = ["check_stiffness", "linear_energy", "add_builtin_springs"]

_POSITION = exu.OutputVariableType.Position
_HIDDEN = {"show": False, "drawSize": -1.0, "color": [-1.0, -1.0, -1.0, -1.0]}


def check_stiffness(stiffness, n: int, kind: str) -> NDArray[np.float64] | None:
    """``None``, or the stiffnesses as an array of shape (n, 3) [N/m] (finite, >= 0)."""
    if stiffness is None:
        return None
    if kind != "position":
        raise ValueError(
            "stiffness applies to position markers only (linear springs along the "
            "global axes); the markerPairs are coordinate markers"
        )
    try:
        k = np.array(stiffness, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(
            f"stiffness must be a sequence of {n} 3-vectors [N/m], got {stiffness!r}"
        ) from None
    if k.shape != (n, 3):
        raise ValueError(
            f"stiffness must have shape ({n}, 3) (one [kx, ky, kz] per marker pair), got {k.shape}"
        )
    if not np.all(np.isfinite(k)) or np.any(k < 0.0):
        bad = np.argwhere(~np.isfinite(k) | (k < 0.0))[0]
        raise ValueError(
            f"stiffness must be finite and >= 0 [N/m], got stiffness[{bad[0]}]"
            f"[{bad[1]}] = {k[tuple(bad)]}"
        )
    return k


def linear_energy(mbs, pairs, k) -> float:
    """Potential energy [J] of the springs ``k`` at the current configuration:
    ``sum 0.5 k_i d_i^2`` with ``d = p1 - p0`` (as Exudyn's built-in Cartesian spring).
    """
    if k is None:
        return 0.0
    get = mbs.GetMarkerOutput
    e = 0.0
    for (m0, m1), ki in zip(pairs, k):
        if ki.any():
            d = get(int(m1), _POSITION) - get(int(m0), _POSITION)
            e += 0.5 * float(np.dot(ki, d * d))
    return e if math.isfinite(e) else math.nan


def add_builtin_springs(mbs, pairs, k, name: str) -> list:
    """Built-in Cartesian springs ``k`` on the pairs (the Python route: its connectors have no
    symbolic law to carry them).
    """
    out = []
    for i, ((m0, m1), ki) in enumerate(zip(pairs, k)):
        if ki.any():
            out.append(
                mbs.AddObject(
                    ObjectConnectorCartesianSpringDamper(
                        name=f"{name}spring{i}" if name else "",
                        markerNumbers=[int(m0), int(m1)],
                        stiffness=[float(x) for x in ki],
                        damping=[0.0, 0.0, 0.0],
                        visualization=_HIDDEN,
                    )
                )
            )
    return out
