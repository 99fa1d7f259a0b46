"""The specimen's linear damping floor, one ratio per mode, as a modal damping matrix.

Real structures damp each mode by its own linear amount (material, boundaries, air), which
``Specimen.modal_damping`` / :meth:`~iwan_element.models.specimens.specimen.Specimen.floor` carry.
The transient routes (the ring-down, the stepped sine) build it into the beams as the modal
damping matrix of the stuck-interface system on the free coordinates,

    C = M Phi diag(2 zeta_r w_r) Phi^T M,

over every mode ``(w_r, phi_r)`` of ``(K0 + G^T diag(KT) G, M)`` (mass-normalised),
``zeta_r = specimen.floor(r)`` for elastic mode ``r`` (numbered as
:func:`~iwan_element.models.modal.linear_modes` numbers them) and the rigid-body modes (and
any elastic mode below 0.5 Hz, which ``linear_modes`` does not number) undamped. Then
``phi_r^T C phi_s = 2 zeta_r w_r delta_rs``: each stuck mode decays at its own floor and the
floor couples no modes. (The stiffness-proportional beam damping used before gave one mode
its floor and every other mode the floor times its frequency ratio.) The matrix is the
damping matrix of the host's generic body (:mod:`~iwan_element.models.simulation.host`); its work is
booked exactly by :class:`FloorWork`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..specimens.specimen import Specimen
from .dispatch import check_specimen
from .model import stuck_key, stuck_modes

__all__ = ["FloorDamping", "floor_damping", "FloorWork"]


@dataclass(frozen=True)
class FloorDamping:
    """The modal damping floor of a specimen on its free coordinates.

    Attributes
    ----------
    C : ndarray, shape (n_free, n_free)
        Damping matrix [N s/m and consistent units].
    omega : ndarray, shape (n_free,)
        Stuck natural frequencies [rad/s], ascending (rigid-body modes first).
    zeta : ndarray, shape (n_free,)
        Damping ratio given to each of them [-] (0 for the rigid-body modes).
    n_rigid : int
        Modes left undamped below the first elastic mode.
    """

    C: np.ndarray
    omega: np.ndarray
    zeta: np.ndarray
    n_rigid: int

    @property
    def active(self) -> bool:
        """True when some mode is damped."""
        return bool(np.any(self.zeta > 0))


def floor_damping(specimen: Specimen) -> FloorDamping:
    """The modal damping matrix of ``specimen``'s floor (module docstring).

    Parameters
    ----------
    specimen : Specimen or SolidSpecimen
        Its ``floor(r)`` gives elastic mode ``r``'s ratio.

    Returns
    -------
    FloorDamping
    """
    check_specimen(specimen)
    L, _, w, V, n_low = stuck_modes(stuck_key(specimen))  # the one stuck eigenproblem
    n_skip = max(L.rigid_body_modes, n_low)
    zeta = np.array([0.0 if k < n_skip else specimen.floor(k - n_skip + 1) for k in range(w.size)])
    MV = L.M @ V
    C = (MV * (2.0 * zeta * w)) @ MV.T
    return FloorDamping(C=0.5 * (C + C.T), omega=w.copy(), zeta=zeta, n_rigid=n_skip)


class FloorWork:
    """Work done by the floor's damping matrix ``C`` (the host's coordinates) [J]: per step
    ``h v_m^T C v_m`` with ``v_m`` the mean of the step's end velocities, which is the
    damping work of the trapezoidal rule exactly (its force is ``C v_m`` over a displacement
    ``h v_m``) and of any second-order scheme to ``O(h^2)``.
    """

    def __init__(self, C):
        self.C = None if C is None else np.asarray(C)
        self.t = self.v = None
        self.total = 0.0

    def step(self, t: float, v: np.ndarray) -> float:
        """Cumulative work up to time ``t`` [s] with the velocities ``v`` of ``C``'s
        coordinates.
        """
        if self.C is not None and self.t is not None and t > self.t:
            vm = 0.5 * (v + self.v)
            self.total += (t - self.t) * float(vm @ self.C @ vm)
        self.t, self.v = t, v.copy()
        return self.total
