"""A discretised Iwan joint: a finite set of parallel Jenkins sliders (for comparison).

Each slider ``i`` is a spring ``k_i`` [N/m] in series with a Coulomb slider that slips when
its spring stretch reaches ``phi_i`` [m] (force ``k_i phi_i``). The continuous density of
paper eq. 3 is lumped into bins:

* ``spacing="log"``: geometric bin edges from ``phi_max * lowest_edge`` to ``phi_max`` plus a
  first bin ``[0, phi_max * lowest_edge]``; each slider's stiffness is the integral of ``rho``
  over its bin and its slip displacement is the bin's ``rho``-weighted mean, so ``KT`` and
  ``Fs`` are reproduced exactly (moment matching).
* ``spacing="uniform"``: ``N`` equal bins with sliders at the midpoints and stiffness
  ``R phi_i**chi dphi``, the rule used by common open-source codes. It under-estimates ``KT``
  (by 2.75 % at ``chi = -0.5, beta = 0.1, N = 100``) and gives no dissipation below
  ``phi_max/(2N)``.

The Dirac spike ``S delta(phi - phi_max)`` is always one extra slider of stiffness ``S`` at
``phi_max`` (if ``beta > 0``).
"""

from __future__ import annotations

import numpy as np

from ..base.validation import check_scalar, finite_array, same_length
from .parameters import IwanParameters
from .protocol import CommittedState

__all__ = ["DiscreteIwan", "slider_distribution"]


#: Largest accepted ``n_sliders`` (a bank of 1e6 sliders is already 1e4 times the 100 that
#: docs/equations.md section 4 shows accurate to ~2e-3).
MAX_SLIDERS = 1_000_000


def slider_distribution(
    params: IwanParameters, n_sliders: int = 100, *, spacing: str = "log", lowest_edge: float = 1e-6
) -> tuple[np.ndarray, np.ndarray]:
    """Slider stiffnesses ``k`` [N/m] and slip displacements ``phi`` [m] for a discretised joint.

    Parameters
    ----------
    params : IwanParameters
    n_sliders : int
        Number of sliders for the continuous part of the density, ``>= 1``.
    spacing : {"log", "uniform"}, keyword-only
        Bin layout (see the module docstring).
    lowest_edge : float, keyword-only
        For ``spacing="log"``: lowest geometric edge as a fraction of ``phi_max``, in
        ``(0, 1)``. Ignored for ``"uniform"``.

    Returns
    -------
    k, phi : ndarray, shape (n_sliders,) or (n_sliders + 1,)
        The spike slider (``k = S`` at ``phi_max``) is appended when ``S > 0``.
    """
    if not isinstance(params, IwanParameters):
        raise ValueError(f"params must be an IwanParameters instance, got {type(params).__name__}")
    if (
        isinstance(n_sliders, bool)
        or not isinstance(n_sliders, (int, np.integer))
        or not 1 <= n_sliders <= MAX_SLIDERS
    ):
        raise ValueError(f"n_sliders must be an integer in [1, {MAX_SLIDERS}], got {n_sliders!r}")
    p = params
    # Written in s = phi/phi_max so that no power of phi_max appears (it overflows for large
    # chi): R phi**chi dphi = (chi+1) K_slider s**chi ds, with K_slider = KT/(1+beta).
    pm, c, Ks = p.phi_max, p.chi, p.K_slider
    if spacing == "uniform":
        ds = 1.0 / n_sliders
        s_mid = (np.arange(n_sliders) + 0.5) * ds
        phi = pm * s_mid
        k = (c + 1.0) * Ks * s_mid**c * ds
    elif spacing == "log":
        lo = check_scalar(
            "lowest_edge", lowest_edge, low=0.0, high=1.0, low_open=True, high_open=True
        )
        if n_sliders == 1:
            edges = np.array([0.0, 1.0])
        else:
            edges = np.concatenate([[0.0], np.geomspace(lo, 1.0, n_sliders)])
        m0 = edges[1:] ** (c + 1.0) - edges[:-1] ** (c + 1.0)
        m1 = edges[1:] ** (c + 2.0) - edges[:-1] ** (c + 2.0)
        k = Ks * m0
        with np.errstate(invalid="ignore", divide="ignore"):
            centre = (c + 1.0) / (c + 2.0) * m1 / m0
        # a bin whose weight underflows (large chi) carries no force: place it at its edge
        phi = pm * np.where(m0 > 0.0, centre, edges[1:])
    else:
        raise ValueError(f"spacing must be 'log' or 'uniform', got {spacing!r}")
    if p.S > 0.0:
        k = np.append(k, p.S)
        phi = np.append(phi, pm)
    return k, phi


class DiscreteIwan(CommittedState):
    """Iwan joint discretised into parallel Jenkins sliders (element protocol).

    Same protocol as :class:`~iwan_element.IwanJoint`: ``trial(u, v=0.0) -> (force,
    stiffness)``, ``commit()``, ``revert()``, ``reset()``, ``force_history(u)`` and the energy
    read-outs. Vectorised with numpy over the sliders.

    Parameters
    ----------
    params : IwanParameters
    n_sliders : int
        Sliders for the continuous density (the spike adds one more), ``>= 1``.
    spacing : {"log", "uniform"}, keyword-only
        ``"log"``: moment-matched log-spaced bins (exact ``KT`` and ``Fs``);
        ``"uniform"``: midpoint rule.
    lowest_edge : float, keyword-only
        Lowest log edge as a fraction of ``phi_max`` (``spacing="log"`` only).
    """

    def __init__(
        self,
        params: IwanParameters,
        n_sliders: int = 100,
        *,
        spacing: str = "log",
        lowest_edge: float = 1e-6,
    ):
        self._p = params
        self._k, self._phi = slider_distribution(
            params, n_sliders, spacing=spacing, lowest_edge=lowest_edge
        )
        self._kphi = self._k * self._phi
        self.spacing = spacing
        self.n_sliders = int(n_sliders)
        self.reset()

    @property
    def params(self) -> IwanParameters:
        """The joint parameters the sliders were built from."""
        return self._p

    @property
    def slider_stiffness(self) -> np.ndarray:
        """Copy of the slider stiffnesses [N/m]."""
        return self._k.copy()

    @property
    def slider_slip(self) -> np.ndarray:
        """Copy of the slider slip displacements [m]."""
        return self._phi.copy()

    def reset(self) -> None:
        """Virgin state: all springs relaxed, energy counters zero."""
        self._z = np.zeros_like(self._k)
        self._u = 0.0
        self._F = 0.0
        self._K = float(self._k.sum())
        self._W = 0.0
        self._D = 0.0
        self.revert()

    def revert(self) -> None:
        """Discard the last trial."""
        self._tz: np.ndarray | None = None
        self._tu = self._u
        self._tF = self._F
        self._tK = self._K

    def trial(self, u: float, v: float = 0.0) -> tuple[float, float]:
        """Force [N] and tangent [N/m] at trial displacement ``u`` [m]; commits nothing."""
        if isinstance(u, (str, bytes, complex, np.ndarray)) or u is None:
            raise ValueError(f"u must be a real number (displacement [m]), got {u!r:.40}")
        u = float(u)
        if not np.isfinite(u):
            raise ValueError(f"u must be finite, got {u}")
        free = self._z + (u - self._u)
        z = np.clip(free, -self._phi, self._phi)
        F = float(self._k @ z)
        K = float(self._k @ (z == free))
        self._tz = z
        self._tu = u
        self._tF = F
        self._tK = K
        return F, K

    def commit(self) -> None:
        """Accept the last trial (no-op if there is none). Each slider dissipates
        ``k phi |slip|`` exactly, since its slip happens at the constant force ``k phi``.
        """
        if self._tz is None:
            return
        slip = np.abs((self._tu - self._u) - (self._tz - self._z))
        self._D += float(self._kphi @ slip)
        self._z = self._tz
        self._u = self._tu
        self._F = self._tF
        self._K = self._tK
        self._W = self.stored_energy + self._D
        self._tz = None

    @property
    def stiffness(self) -> float:
        """Committed tangent [N/m]."""
        return self._K

    @property
    def stored_energy(self) -> float:
        """Elastic energy in the slider springs, ``sum k z**2 / 2`` [J] (committed)."""
        return 0.5 * float(self._k @ (self._z * self._z))

    def force_history(self, u, v=None) -> np.ndarray:
        """Forces [N] for a whole history ``u`` [m], shape (n,), from the virgin state (on a
        private copy; this element is untouched). Rate independent: velocities ``v`` [m/s]
        (shape (n,)), accepted like every element's, are checked and do not change the
        forces.
        """
        arr = finite_array("u", u, ndim=1)
        if v is not None:
            same_length(u=arr, v=finite_array("v", v, ndim=1))
        k, phi = self._k, self._phi
        z = np.zeros_like(k)
        out = np.empty_like(arr)
        prev = 0.0
        for i, ui in enumerate(arr.tolist()):
            z = np.clip(z + (ui - prev), -phi, phi)
            out[i] = k @ z
            prev = ui
        return out

    def __repr__(self) -> str:
        return f"DiscreteIwan({self._p!r}, n_sliders={self.n_sliders}, spacing={self.spacing!r})"
