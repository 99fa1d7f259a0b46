"""A solid (finite-element) lap-jointed specimen that the 1-D analyses accept.

:class:`SolidSpecimen` pairs the 1-D :class:`~iwan_element.models.specimens.specimen.Specimen` (the
interface law, bolts, preload, friction, sensor, damping floor, amplitude range: everything
that is not the bodies' geometry) with a :class:`SolidModel`: the reduced linear system of the
two meshed halves (:class:`~iwan_element.models.linear.LinearSystem`, built by
:mod:`~iwan_element.models.solid.build`) and the contact patches on the lap
(:class:`PatchLayout`). :func:`~iwan_element.models.reduced.dispatch.linear_system` and
:func:`~iwan_element.models.reduced.dispatch.contact_points` dispatch on it, so
:func:`~iwan_element.models.modal.natural_frequencies` and
:func:`~iwan_element.models.modal.modal_amplitude_curve` run on the solid unchanged.

Contact points of a solid: every patch carries two uncoupled Iwan elements, one per
tangential direction of the lap plane (``x`` along the beam, then ``y`` across it), each with
``Fs = mu N_patch`` and ``KT = k_t A_patch (p/p_mean)**m`` (the 1-D law,
:func:`~iwan_element.models.specimens.contact.points_from_forces`). The entries of
:class:`~iwan_element.models.specimens.contact.ContactPoints` therefore come in pairs (patch 0 x,
patch 0 y, patch 1 x, ...), and ``normal_force`` repeats each patch's force twice: its sum is
twice the bolts' preload. Two uncoupled directions make a square friction limit: exact for
a slip along one axis (the height-bending modes slip along ``x``), ``sqrt(2)`` too strong for a
diagonal slip (docs/solid.md).
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields, replace
from typing import TYPE_CHECKING

import numpy as np

from ..linear.system import attach_setup
from ..specimens.contact import ContactPoints, points_from_forces
from ..specimens.specimen import InterfaceModel, Specimen

if TYPE_CHECKING:
    from ..linear.system import LinearSystem

__all__ = ["PatchLayout", "SolidModel", "SolidSpecimen", "solid_contact_points", "clamp_stiffness"]

# Specimen fields a SolidSpecimen may change without rebuilding its bodies: they enter only
# the Iwan elements, the patches' normal springs (the reduction holds the normal gaps'
# attachment shapes) and the analyses' damping floor, amplitudes and effects, not M, Kb, G
_FREE_FIELDS = {
    "name",
    "preload",
    "friction",
    "amplitude_range",
    "modal_damping",
    "calibrated_range",
    "effects",
    "interface_effects",
    "reference",
    "setup",
    "youngs_modulus",
    "density",
}
_FREE_INTERFACE = {
    "stiffness_per_area",
    "stiffness_pressure_exponent",
    "chi",
    "beta",
    "damping_floor",
    "normal_stiffness_per_area",
}


@dataclass(frozen=True, eq=False)
class PatchLayout:
    """Contact patches of the lap: cells of a grid on the lap plane with contact pressure.

    Attributes
    ----------
    x, y : ndarray, shape (n,)
        Patch points [m], along the assembly and across the width: the centroid of the
        patch's contact area (the part of its cell where the pressure is > 0), where the
        patch's slips are measured.
    normal_force : ndarray, shape (n,)
        Integral of the cone pressure over the patch [N] at ``preload`` per bolt.
    area : ndarray, shape (n,)
        Contact area of the patch (where the pressure is > 0) [m^2].
    preload : float
        Bolt preload the forces were integrated at [N].
    size : tuple of 2 floats
        Cell size along and across the beam [m].
    cells : ndarray, shape (n, 2)
        Centres of the patches' grid cells [m].
    """

    x: np.ndarray
    y: np.ndarray
    normal_force: np.ndarray
    area: np.ndarray
    preload: float
    size: tuple
    cells: np.ndarray

    def __len__(self) -> int:
        return int(self.x.size)


@dataclass(frozen=True, eq=False)
class SolidModel:
    """The reduced linear system of two solid halves and their contact patches.

    Attributes
    ----------
    system : LinearSystem
        Reduced coordinates: ``M`` (identity), ``K0`` (bodies and normal patch springs at
        the normal stiffness per area the model was built with), ``Kb`` (bodies), ``G``
        (2 rows per patch: the tangential slips ``x`` and ``y`` of body B's patch average
        minus body A's), ``S`` (the sensor node's ``z`` displacement); ``rigid_body_modes``
        6 free-free, 0 clamped.
    patches : PatchLayout
    normal_gaps : ndarray, shape (n_patches, n_reduced)
        The patches' normal gaps ``z`` (body B's patch average minus body A's) on the
        reduced coordinates: ``K0 = Kb + normal_gaps^T diag(k_n A) normal_gaps``.
    info : dict
        Sizes and wall times (``n_full``, ``n_reduced``, ``n_modes``, ``mesh_s``,
        ``reduction_s``, ...), JSON-safe.
    full : dict or None
        The full sparse matrices (``M``, ``K0``, ``Kb``, ``G``, ``S``), the reduction basis
        ``basis`` and the kept full coordinates ``free`` when built with ``keep_full=True``
        (for checking the reduction), else ``None``.
    axis : tuple or None
        ``(x, rows)``: positions [m] every millimetre along the assembly and, per position,
        the reduced row of the section's z displacement there (``solid.readout._point_weights``)
        (read as ``S``; the ring-down's sensors), shape ``(len(x), n_reduced)``.
    material : tuple or None
        ``(youngs_modulus [Pa], density [kg/m^3])`` the bodies were built with; a specimen
        with other values scales the bodies' stiffness and mass by the ratios (a homogeneous
        material: the reduction basis stays a Ritz basis of the scaled bodies).
    clamp_rows : ndarray or None
        ``(6, n_reduced)``: the clamped face's rigid-body fit (translations, rotations) on
        the reduced coordinates when the bodies were built on a setup's clamp springs
        (their attachment shapes are in the basis, so the springs may change after the
        build); ``None``: a rigid clamp, or free-free.
    """

    system: LinearSystem
    patches: PatchLayout
    normal_gaps: np.ndarray
    info: dict = field(default_factory=dict)
    full: dict | None = field(default=None, repr=False)
    axis: tuple | None = field(default=None, repr=False)
    material: tuple | None = None
    clamp_rows: np.ndarray | None = field(default=None, repr=False)


@dataclass(frozen=True)
class SolidSpecimen:
    """A specimen whose two halves are solid finite-element bodies (module docstring).

    Parameters
    ----------
    specimen : Specimen
        Everything but the bodies' geometry: bolts, preload, friction, interface law, sensor
        position, boundary, damping floor, amplitude range, effects. Its fields are read
        through the SolidSpecimen (``solid.friction``, ``solid.interface``, ...).
    model : SolidModel
        The reduced bodies and patches, built for this specimen's geometry and boundary
        (:func:`~iwan_element.models.solid.solid_specimen`).
    """

    specimen: Specimen
    model: SolidModel

    def __post_init__(self):
        if not isinstance(self.specimen, Specimen):
            raise TypeError(f"specimen must be a Specimen, got {type(self.specimen).__name__}")
        if not isinstance(self.model, SolidModel):
            raise TypeError(f"model must be a SolidModel, got {type(self.model).__name__}")
        if (self.specimen.setup.clamp is None) != (
            self.model.clamp_rows is None
        ) and self.specimen.boundary != "free-free":
            raise ValueError(
                "setup.clamp: the solid bodies were built "
                + ("with a rigid clamp" if self.model.clamp_rows is None else "on clamp springs")
                + "; a clamp held rigidly and one on springs need different "
                "bodies: build the solid with the setup it is to carry"
            )

    def __getattr__(self, name):
        if name in ("specimen", "model") or name.startswith("__"):
            raise AttributeError(name)
        return getattr(self.specimen, name)

    def replace(self, **changes) -> SolidSpecimen:
        """A copy with interface or test fields changed (``friction``, ``preload``,
        ``stiffness_per_area``, ``chi``, ``beta``, ``damping_floor``, ``modal_damping``,
        ``amplitude_range``, ``calibrated_range``, ``effects``, ``normal_stiffness_per_area``,
        ...). Fields that change the bodies, the patches or the sensor need a new build
        (ValueError).
        """
        inames = {f.name for f in fields(InterfaceModel)}
        fixed = set(changes) - _FREE_FIELDS - _FREE_INTERFACE - {"interface"}
        if "interface" in changes:
            old, new = self.specimen.interface, changes["interface"]
            fixed |= {n for n in inames - _FREE_INTERFACE if getattr(old, n) != getattr(new, n)}
        if fixed:
            raise ValueError(
                f"{sorted(fixed)} change the solid bodies or their patches; build a "
                "new solid (models.solid_preset / models.solid.solid_specimen) "
                f"instead; a SolidSpecimen may change {sorted(_FREE_FIELDS | _FREE_INTERFACE)}"
            )
        return SolidSpecimen(self.specimen.replace(**changes), self.model)

    def with_effects(
        self, effects: dict, *, mode: int = 1, calibrated_range=None, form: str = "modal"
    ) -> SolidSpecimen:
        """:meth:`Specimen.with_effects` on the solid (the bodies unchanged)."""
        return SolidSpecimen(
            self.specimen.with_effects(
                effects, mode=mode, calibrated_range=calibrated_range, form=form
            ),
            self.model,
        )

    def linear_system(self) -> LinearSystem:
        """The reduced :class:`~iwan_element.models.linear.LinearSystem`: the bodies scaled
        to this specimen's ``youngs_modulus`` and ``density`` (:attr:`SolidModel.material`),
        ``K0`` holding the patches' normal springs at its
        ``interface.normal_stiffness_per_area`` (``k_n A`` per patch on the normal gaps), and
        its setup's clamp springs on the clamped face's rigid-body fit
        (:attr:`SolidModel.clamp_rows`) and masses and shaker on the axis rows
        (:func:`~iwan_element.models.linear.attach_setup`).
        """
        sysm, Gn = self.model.system, self.model.normal_gaps
        kn = self.specimen.interface.normal_stiffness_per_area * self.model.patches.area
        sE, sR = 1.0, 1.0
        if self.model.material is not None:
            sE = self.specimen.youngs_modulus / self.model.material[0]
            sR = self.specimen.density / self.model.material[1]
        Kb = sE * sysm.Kb
        K0 = Kb + Gn.T @ (kn[:, None] * Gn)
        if self.model.clamp_rows is not None:
            Gc = self.model.clamp_rows
            K0 = K0 + Gc.T @ (clamp_stiffness(self.specimen.setup.clamp)[:, None] * Gc)
        L = replace(sysm, M=sR * sysm.M, Kb=Kb, K0=K0, Gn=Gn)
        return attach_setup(
            L, self.specimen.setup, lambda x: (None, self.axis_rows(np.asarray(x, float)), None)
        )

    def axis_rows(self, positions) -> np.ndarray:
        """Reduced rows of the z displacement at ``positions`` [m] along the assembly (the
        section's deflection, read as the sensor's ``S`` is: ``solid.readout._point_weights``),
        interpolated linearly between the millimetres of :attr:`SolidModel.axis`: shape
        ``(n, n_reduced)``.
        """
        if self.model.axis is None:
            raise ValueError(
                "this solid model holds no axis rows: build it with models.solid.solid_specimen"
            )
        x, rows = self.model.axis
        u = np.clip(np.asarray(positions, float) / (x[1] - x[0]), 0, x.size - 1)
        k = np.minimum(np.floor(u).astype(int), x.size - 2)
        f = (u - k)[:, None]
        return (1 - f) * rows[k] + f * rows[k + 1]

    def contact_points(self) -> ContactPoints:
        """The patches' Iwan elements (two per patch, module docstring)."""
        return solid_contact_points(self.specimen, self.model.patches)


def clamp_stiffness(clamp) -> np.ndarray:
    """The six springs of a setup's clamp on :attr:`SolidModel.clamp_rows`: its
    translational stiffness on the face's translations [N/m], its rotational one on the
    face's rotations [N m/rad].
    """
    k, kr = clamp.translational, clamp.rotational
    return np.array([k, k, k, kr, kr, kr])


def solid_contact_points(specimen: Specimen, patches: PatchLayout) -> ContactPoints:
    """Iwan elements of the patches for a specimen's interface law: per patch an ``x`` and a
    ``y`` element (module docstring); the normal forces scale with ``specimen.preload``.
    """
    N = patches.normal_force * (specimen.preload / patches.preload)
    two = np.repeat
    return points_from_forces(specimen, two(patches.x, 2), two(N, 2), two(patches.area, 2))
