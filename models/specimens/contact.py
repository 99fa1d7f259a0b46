"""Contact pressure in the lap and the Iwan element of each contact point.

Pressure model (docs/equations.md section 7, "Contact pressure"): each bolt clamps the two lap
halves through a frustum of half-apex angle ``a`` (Shigley/Budynas & Nisbett ch. 8; Osgood
25-33 deg) starting at the washer, so at the interface the pressure is confined to a disc of
radius ``r_c = D_w/2 + t tan(a)`` (``t`` the thickness of one lap half), zero in the bolt hole
and beyond ``r_c``. Inside, the shape is ``"linear-cone"`` (falling linearly from the hole edge
to zero at ``r_c``) or ``"uniform-cone"``; the published shapes (Gould & Mikic 1972,
Fernlund 1970) were not verified, so the shape is a documented option. Each bolt's field is
clipped to the lap (its length and the beam width) and scaled so that its integral over the
contact equals the bolt preload; overlapping cones add.

Contact points: the lap is cut into ``n_points`` strips of equal length across the full
width; point ``i`` sits at the strip centre with normal force ``N_i`` (integral of ``p``
over the strip) and contact area ``A_i`` (where ``p > 0``). Its Iwan element has
``Fs_i = mu N_i`` and ``KT_i = k_t A_i (p_i / p_mean)**m`` (``k_t`` stiffness per area,
:class:`~iwan_element.models.specimens.specimen.InterfaceModel`); strips without contact get no
element. Points near a cone's edge carry little pressure but comparable area, so they reach
macroslip first: the microslip of real lap joints.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from iwan_element import IwanParameters

from .specimen import Specimen

__all__ = ["ContactPoints", "pressure_field", "beam_contact_points", "points_from_forces"]


def pressure_field(
    specimen: Specimen, *, nx: int = 600, ny: int = 41
) -> tuple[NDArray[np.floating], NDArray[np.floating], NDArray[np.floating]]:
    """Contact pressure on a grid over the lap.

    Returns
    -------
    x : ndarray, shape (nx,)
        Cell centres along the lap from its start [m].
    y : ndarray, shape (ny,)
        Cell centres across the width [m].
    p : ndarray, shape (nx, ny)
        Pressure [Pa]; ``sum(p) * dx * dy`` equals ``preload * n_bolts``.
    """
    s = specimen
    dx, dy = s.overlap / nx, s.width / ny
    x = (np.arange(nx) + 0.5) * dx
    y = (np.arange(ny) + 0.5) * dy - 0.5 * s.width
    X, Y = np.meshgrid(x, y, indexing="ij")
    rh, rc = 0.5 * s.bolt_diameter, s.cone_radius
    p = np.zeros_like(X)
    for xb in s.bolt_positions:
        r = np.hypot(X - xb, Y)
        inside = (r >= rh) & (r <= rc)
        if s.interface.pressure == "linear-cone":
            shape = np.where(inside, (rc - r) / (rc - rh), 0.0)
        else:
            shape = inside.astype(float)
        total = shape.sum() * dx * dy
        if total <= 0:
            raise ValueError(
                "the pressure cone of a bolt has no area on the lap; check the "
                "bolt_positions, bolt_diameter and washer_diameter"
            )
        p += shape * (s.preload / total)
    return x, y, p


@dataclass(frozen=True)
class ContactPoints:
    """The contact points of a lap interface.

    Attributes
    ----------
    x : ndarray, shape (n,)
        Position along the assembly [m] (from beam A's end).
    normal_force, area : ndarray, shape (n,)
        Normal force [N] and contact area [m^2] of each point.
    params : tuple of IwanParameters
        Tangential Iwan element of each point.
    normal_stiffness : ndarray, shape (n,)
        Normal contact stiffness of each point [N/m].
    """

    x: np.ndarray
    normal_force: np.ndarray
    area: np.ndarray
    params: tuple
    normal_stiffness: np.ndarray

    def __len__(self) -> int:
        return len(self.params)

    @property
    def Fs(self) -> np.ndarray:
        """Slip force ``Fs`` of each point's Iwan element [N], shape (n,)."""
        return np.array([p.Fs for p in self.params])

    @property
    def KT(self) -> np.ndarray:
        """Tangential stiffness ``KT`` of each point's Iwan element [N/m], shape (n,)."""
        return np.array([p.KT for p in self.params])

    @property
    def phi_max(self) -> np.ndarray:
        """Slip displacement ``phi_max`` of each point's strongest slider [m], shape (n,)."""
        return np.array([p.phi_max for p in self.params])


def beam_contact_points(specimen: Specimen) -> ContactPoints:
    """Contact points, normal forces and Iwan elements of a 1-D specimen's interface (module
    doc).

    The ``"lumped"`` interface puts two points per bolt at ``+-r_c/2`` with half the bolt's
    preload and half its cone area each (equal sharing, no pressure gradient). The analyses
    read :func:`~iwan_element.models.reduced.dispatch.contact_points`, which also takes a
    :class:`~iwan_element.models.solid.specimen.SolidSpecimen` (its patches' elements).
    """
    s, itf = specimen, specimen.interface
    if itf.model == "lumped":
        xs: list[float] = []  # [m]
        Ns: list[float] = []  # [N]
        As: list[float] = []  # [m^2]
        rc, rh = s.cone_radius, 0.5 * s.bolt_diameter
        cone_area = np.pi * (rc * rc - rh * rh)
        for xb in s.bolt_positions:
            for d in (-0.5 * rc, 0.5 * rc):
                xs.append(min(max(xb + d, 0.0), s.overlap))
                Ns.append(0.5 * s.preload)
                As.append(0.5 * cone_area)
        x, N, A = np.array(xs), np.array(Ns), np.array(As)
    else:
        n = itf.n_points
        xg, _, p = pressure_field(s, nx=max(600, 15 * n))
        dA = (s.overlap / len(xg)) * (s.width / p.shape[1])
        strip = np.minimum((xg / s.overlap * n).astype(int), n - 1)
        N = np.bincount(strip, weights=p.sum(axis=1) * dA, minlength=n)
        A = np.bincount(strip, weights=(p > 0).sum(axis=1) * dA, minlength=n)
        x = (np.arange(n) + 0.5) * s.overlap / n
        keep = (N > 1e-9 * s.preload) & (A > 0)
        x, N, A = x[keep], N[keep], A[keep]
    return points_from_forces(s, x + s.lap_start, N, A)


def points_from_forces(specimen: Specimen, x, normal_force, area) -> ContactPoints:
    """The Iwan elements of contact points with given normal forces [N] and contact areas
    [m^2] (``Fs_i = mu N_i``, ``KT_i = k_t A_i (p_i / p_mean)**m``, module docstring), at
    positions ``x`` [m] along the assembly; the 1-D strips and the solid's patches share it.
    """
    s, itf = specimen, specimen.interface
    x, N, A = (np.asarray(v, float) for v in (x, normal_force, area))
    p_i = N / A
    p_mean = N.sum() / A.sum()
    KT = itf.stiffness_per_area * A * (p_i / p_mean) ** itf.stiffness_pressure_exponent
    params = tuple(
        IwanParameters(Fs=float(s.friction * n_), KT=float(k), chi=itf.chi, beta=itf.beta)
        for n_, k in zip(N, KT)
    )
    return ContactPoints(
        x=x,
        normal_force=N,
        area=A,
        params=params,
        normal_stiffness=itf.normal_stiffness_per_area * A,
    )
