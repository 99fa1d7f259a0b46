"""Two-beam lap-joint specimens: one validated description.

A :class:`Specimen` says everything the models need about a bolted lap-jointed beam: the two
beams (length, width, thickness outside and inside the lap), material, overlap, bolts
(positions, preload, washer), friction coefficient, boundary conditions, excitation and sensor
points, the amplitude range a test covers, and the contact-interface model
(:class:`InterfaceModel`). Coordinates run along the assembly from the free or clamped end of
beam A (``x = 0``); beam A occupies ``[0, L]``, beam B ``[L - overlap, 2L - overlap]``.

The published presets are in :mod:`~iwan_element.models.specimens.presets`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields, replace

from iwan_element.base.validation import check_int, plain_fields, plain_number

from .effects import InterfaceEffect, SpecimenEffect, check_range
from .setups import Setup

__all__ = ["InterfaceModel", "Excitation", "Specimen"]

_BOUNDARIES = ("free-free", "clamped-free", "clamped-driven")
_EXCITATIONS = ("hammer", "shaker", "base")
_PRESSURE = ("linear-cone", "uniform-cone")
_INTERFACE = ("distributed", "lumped")
_THEORIES = ("timoshenko", "euler-bernoulli")


def _pos(name, v, *, zero=False):
    if (
        isinstance(v, bool)
        or not isinstance(v, (int, float))
        or not math.isfinite(v)
        or v < 0
        or (v == 0 and not zero)
    ):
        raise ValueError(f"{name} must be a finite number {'>=' if zero else '>'} 0, got {v!r}")
    return float(v)


@dataclass(frozen=True)
class InterfaceModel:
    """Contact interface of the lap: how pressure becomes Iwan elements.

    Parameters
    ----------
    model : {"distributed", "lumped"}
        ``"distributed"``: ``n_points`` contact points along the lap, each an Iwan element with
        ``Fs_i = mu N_i`` (``N_i`` the normal force of its strip from the pressure cones) and
        ``KT_i = stiffness_per_area * A_i * (p_i / p_mean)**stiffness_pressure_exponent``
        (``A_i`` the strip's contact area, ``p_i = N_i / A_i``). ``"lumped"``: two points per
        bolt at +-r_c/2, each with half the bolt's slip force ``mu P`` and half its cone area.
    n_points : int
        Contact points (strips) along the lap, ``>= 2``.
    stiffness_per_area : float
        Tangential stiffness per unit contact area [N/m^3] (Pa/m). Assumption: a flat
        stuck contact has a stiffness per area set by roughness and material (Mindlin's
        tangential compliance of asperities), independent of pressure unless
        ``stiffness_pressure_exponent`` > 0; it is calibrated, not predicted.
    stiffness_pressure_exponent : float
        ``m`` above, ``>= 0`` (0: stiffness follows area only).
    normal_stiffness_per_area : float
        Normal contact stiffness per unit area [N/m^3].
    chi, beta : float
        Iwan exponent and spike ratio of every point (docs/equations.md section 2 ranges).
    damping_floor : float
        Modal damping ratio of the linear mode from material and boundaries [-], ``>= 0``
        (a viscous floor, docs/equations.md section 7: it adds to the joint's).
    pressure : {"linear-cone", "uniform-cone"}
        Pressure shape inside each bolt's cone (zero in the hole and beyond ``r_c``):
        decreasing linearly from the hole edge to zero at ``r_c``, or uniform.
    cone_angle_deg : float
        Half-apex angle of the pressure frustum [deg] (Shigley: 30; Osgood: 25-33).
    """

    model: str = "distributed"
    n_points: int = 40
    stiffness_per_area: float = 1.0e12
    stiffness_pressure_exponent: float = 0.0
    normal_stiffness_per_area: float = 1.0e13
    chi: float = -0.5
    beta: float = 0.1
    damping_floor: float = 0.0
    pressure: str = "linear-cone"
    cone_angle_deg: float = 30.0

    def __post_init__(self):
        plain_fields(self)
        if self.model not in _INTERFACE:
            raise ValueError(f"interface model must be one of {_INTERFACE}, got {self.model!r}")
        if (
            isinstance(self.n_points, bool)
            or not isinstance(self.n_points, int)
            or self.n_points < 2
        ):
            raise ValueError(f"n_points must be an integer >= 2, got {self.n_points!r}")
        _pos("stiffness_per_area", self.stiffness_per_area)
        _pos("normal_stiffness_per_area", self.normal_stiffness_per_area)
        _pos("stiffness_pressure_exponent", self.stiffness_pressure_exponent, zero=True)
        _pos("damping_floor", self.damping_floor, zero=True)
        if self.damping_floor >= 0.2:
            raise ValueError(f"damping_floor is a ratio < 0.2, got {self.damping_floor!r}")
        if not (isinstance(self.chi, (int, float)) and -1.0 < self.chi <= 1.0):
            raise ValueError(f"chi must be in (-1, 1], got {self.chi!r}")
        _pos("beta", self.beta, zero=True)
        if self.pressure not in _PRESSURE:
            raise ValueError(f"pressure must be one of {_PRESSURE}, got {self.pressure!r}")
        if not (
            isinstance(self.cone_angle_deg, (int, float)) and 5.0 <= self.cone_angle_deg <= 60.0
        ):
            raise ValueError(f"cone_angle_deg must be in [5, 60], got {self.cone_angle_deg!r}")


@dataclass(frozen=True)
class Excitation:
    """How the test excites the specimen: ``kind`` in {"hammer", "shaker", "base"} and the
    ``position`` [m] along the assembly (ignored for base motion).
    """

    kind: str = "hammer"
    position: float = 0.0

    def __post_init__(self):
        plain_fields(self)
        if self.kind not in _EXCITATIONS:
            raise ValueError(f"excitation kind must be one of {_EXCITATIONS}, got {self.kind!r}")
        _pos("excitation position", self.position, zero=True)


@dataclass(frozen=True)
class Specimen:
    """A two-beam bolted lap-joint specimen (SI units). See the module docstring.

    Parameters
    ----------
    name : str
    beam_length : float
        Length of each beam [m].
    width : float
        [m].
    thickness : float
        Beam height (bending direction) outside the lap [m].
    lap_thickness : float
        Height of each beam inside the lap [m] (``thickness`` for two plain stacked bars,
        ``thickness/2`` for the Brake-Reuss beam's stepped halves).
    youngs_modulus, density : float
        [Pa], [kg/m^3].
    poissons_ratio : float
        [-], in (-1, 0.5): the shear modulus ``E / (2 (1 + nu))`` of the Timoshenko beams (the
        solid bodies take theirs at meshing).
    shear_coefficient : float
        Timoshenko's ``kappa`` of the section [-], in (0, 1] (5/6 for a rectangle).
    beam_theory : {"timoshenko", "euler-bernoulli"}
        The 1-D beams' theory (:mod:`~iwan_element.models.beam.elements`): shear and rotary
        inertia, or neither.
    overlap : float
        Lap length [m], ``< beam_length``.
    bolt_positions : tuple of float
        Bolt centres from the start of the lap [m], inside ``(0, overlap)``.
    preload : float
        Preload per bolt [N].
    bolt_diameter, washer_diameter : float
        [m]; the washer (or head) diameter starts the pressure cone.
    friction : float
        Friction coefficient mu of the interface [-].
    boundary : {"free-free", "clamped-free", "clamped-driven"}
        Clamped means beam A clamped at ``x = 0``; driven means beam B's far end held
        transversely and driven axially (the quasi-static test).
    excitation : Excitation
    sensor_position : float
        Where the response amplitude is read [m] along the assembly (transverse displacement).
    amplitude_range : tuple of 2 floats
        Documented (measured, for published specimens) displacement amplitude range at the
        sensor [m].
    modal_damping : tuple of float
        Linear (floor) damping ratio of each elastic mode [-], mode 1 first: material,
        boundary and air damping, which differ by mode. A mode beyond the tuple (or every mode
        when it is empty) takes ``interface.damping_floor``. :meth:`floor` reads it; QSMA,
        the frequency-domain routes and the transient build their damping from it.
    calibrated_range : tuple of 2 floats or None
        Sensor amplitudes [m] the interface was calibrated on (``None``: not calibrated, or
        unknown). :func:`~iwan_element.models.modal.modal_amplitude_curve` warns for
        amplitudes outside it.
    effects : tuple of SpecimenEffect
        Vibration effects beyond the Iwan interface (hardening, macroslip onset, ...) in their
        modal form on one mode (``VibrationDiagnosis.augment(..., form="modal")``); QSMA, the
        frequency-domain routes and the transient apply them to that mode.
    interface_effects : tuple of InterfaceEffect
        The same effects in the joint (physical form, ``VibrationDiagnosis.augment``'s
        default): a law at contact points that every analysis runs, in every mode
        (:mod:`~iwan_element.models.specimens.effects`).
    interface : InterfaceModel
    setup : Setup
        What the test attaches (sensor masses, a shaker, a clamp that is not rigid;
        :mod:`~iwan_element.models.specimens.setups`); every analysis includes it.
    n_elements : int
        Beam elements per beam (split between the lap and the rest by length), ``>= 4``.
    reference : str
        Where the numbers come from.
    """

    name: str = "custom"
    beam_length: float = 0.2
    width: float = 0.04
    thickness: float = 0.01
    lap_thickness: float = 0.01
    youngs_modulus: float = 2.1e11
    density: float = 7850.0
    poissons_ratio: float = 0.3
    shear_coefficient: float = 5.0 / 6.0
    beam_theory: str = "timoshenko"
    overlap: float = 0.05
    bolt_positions: tuple = (0.025,)
    preload: float = 30.0e3
    bolt_diameter: float = 0.016
    washer_diameter: float = 0.030
    friction: float = 0.3
    boundary: str = "clamped-free"
    excitation: Excitation = field(default_factory=Excitation)
    sensor_position: float = 0.35
    amplitude_range: tuple = (1e-6, 1e-4)
    interface: InterfaceModel = field(default_factory=InterfaceModel)
    modal_damping: tuple = ()
    calibrated_range: tuple | None = None
    effects: tuple = ()
    interface_effects: tuple = ()
    setup: Setup = field(default_factory=Setup)
    n_elements: int = 16
    reference: str = ""

    def __post_init__(self):
        plain_fields(self)
        self._check_beam()
        bp = tuple(float(b) for b in self.bolt_positions)
        if not bp or any(not (0.0 < b < self.overlap) for b in bp):
            raise ValueError(
                f"bolt_positions must be a non-empty sequence inside (0, overlap="
                f"{self.overlap}) [m], got {self.bolt_positions!r}"
            )
        object.__setattr__(self, "bolt_positions", bp)
        self._check_holes()
        self._check_placements()
        object.__setattr__(
            self, "amplitude_range", check_range("amplitude_range", self.amplitude_range)
        )
        if self.calibrated_range is not None:
            object.__setattr__(
                self, "calibrated_range", check_range("calibrated_range", self.calibrated_range)
            )
        md = self.modal_damping
        md = None if isinstance(md, (str, bytes)) else tuple(plain_number(z) for z in md)
        if md is None or any(
            isinstance(z, bool)
            or not isinstance(z, (int, float))
            or not math.isfinite(z)
            or not 0.0 <= z < 0.2
            for z in md
        ):
            raise ValueError(
                "modal_damping must be a sequence of damping ratios in [0, 0.2), "
                f"one per elastic mode from mode 1, got {self.modal_damping!r}"
            )
        object.__setattr__(self, "modal_damping", tuple(float(z) for z in md))
        eff = tuple(self.effects)
        if not all(isinstance(e, SpecimenEffect) for e in eff):
            raise ValueError("effects must be a sequence of SpecimenEffect")
        object.__setattr__(self, "effects", eff)
        ife = tuple(self.interface_effects)
        if not all(isinstance(e, InterfaceEffect) for e in ife):
            raise ValueError("interface_effects must be a sequence of InterfaceEffect")
        if len({e.name for e in ife}) != len(ife):
            raise ValueError("interface_effects: each effect at most once")
        object.__setattr__(self, "interface_effects", ife)
        if (
            isinstance(self.n_elements, bool)
            or not isinstance(self.n_elements, int)
            or self.n_elements < 4
        ):
            raise ValueError(f"n_elements must be an integer >= 4, got {self.n_elements!r}")

    def _check_beam(self):
        """The material, section, beam theory, setup type and lap dimensions."""
        for n in (
            "beam_length",
            "width",
            "thickness",
            "lap_thickness",
            "youngs_modulus",
            "density",
            "overlap",
            "preload",
            "bolt_diameter",
            "washer_diameter",
            "friction",
        ):
            _pos(n, getattr(self, n))
        nu, kap = self.poissons_ratio, self.shear_coefficient
        if isinstance(nu, bool) or not isinstance(nu, (int, float)) or not -1.0 < nu < 0.5:
            raise ValueError(f"poissons_ratio must be in (-1, 0.5), got {nu!r}")
        if isinstance(kap, bool) or not isinstance(kap, (int, float)) or not 0.0 < kap <= 1.0:
            raise ValueError(f"shear_coefficient must be in (0, 1], got {kap!r}")
        if self.beam_theory not in _THEORIES:
            raise ValueError(f"beam_theory must be one of {_THEORIES}, got {self.beam_theory!r}")
        if not isinstance(self.setup, Setup):
            raise ValueError(f"setup must be a Setup, got {type(self.setup).__name__}")
        if self.overlap >= self.beam_length:
            raise ValueError(
                f"overlap must be < beam_length ({self.beam_length}), got {self.overlap}"
            )
        if self.lap_thickness > self.thickness:
            raise ValueError("lap_thickness must be <= thickness")
        if self.washer_diameter <= self.bolt_diameter:
            raise ValueError("washer_diameter must be > bolt_diameter")

    def _check_holes(self):
        """The bolt holes and washers against the part they go through: every hole (diameter
        ``bolt_diameter``) narrower than the beam's ``width`` and inside the lap, no two holes
        overlapping, the washer no wider than the beam. The one geometry rule of the 1-D
        strips and the solid bodies (:func:`~iwan_element.models.solid.lap_beam_parts` cuts
        these holes): a hole as wide as the beam cuts it in two, and a washer wider than the
        beam hangs over its edges, where the pressure cone that starts at the washer
        (``cone_radius``) has no material to press.
        """
        d, w = self.bolt_diameter, self.width
        if d >= w:
            raise ValueError(
                f"bolt_diameter {d * 1e3:.4g} mm does not fit the beam: a hole as wide as or "
                f"wider than the beam's width {w * 1e3:.4g} mm cuts the lap in two (the "
                "hole must be narrower than the width)"
            )
        if self.washer_diameter > w:
            raise ValueError(
                f"washer_diameter {self.washer_diameter * 1e3:.4g} mm is wider than the "
                f"beam's width {w * 1e3:.4g} mm: the washer would hang over the lap's edges, "
                "where the pressure cone that starts at it has no material"
            )
        for k, b in enumerate(self.bolt_positions):
            if b - 0.5 * d <= 0.0 or b + 0.5 * d >= self.overlap:
                raise ValueError(
                    f"bolt_positions: the hole of bolt {k + 1} at {b * 1e3:.4g} mm (diameter "
                    f"{d * 1e3:.4g} mm) reaches beyond the lap [0, {self.overlap * 1e3:.4g}] mm"
                )
        bp = sorted(self.bolt_positions)
        for b0, b1 in zip(bp, bp[1:]):
            if b1 - b0 <= d:
                raise ValueError(
                    f"bolt_positions: the holes at {b0 * 1e3:.4g} and {b1 * 1e3:.4g} mm "
                    f"(diameter {d * 1e3:.4g} mm) overlap"
                )

    def _check_placements(self):
        """The boundary, excitation, interface and sensor, the setup's attachments on the
        assembly, its clamp only on a clamped beam.
        """
        if self.boundary not in _BOUNDARIES:
            raise ValueError(f"boundary must be one of {_BOUNDARIES}, got {self.boundary!r}")
        if not isinstance(self.excitation, Excitation):
            raise ValueError("excitation must be an Excitation")
        if not isinstance(self.interface, InterfaceModel):
            raise ValueError("interface must be an InterfaceModel")
        if not 0.0 <= self.sensor_position <= self.total_length:
            raise ValueError(
                f"sensor_position must be in [0, {self.total_length}] m, "
                f"got {self.sensor_position!r}"
            )
        if self.excitation.position > self.total_length:
            raise ValueError("excitation position must lie on the assembly")
        for what, x in [(m.name, m.position) for m in self.setup.masses] + (
            [("the shaker", self.setup.shaker.position)] if self.setup.shaker is not None else []
        ):
            if not 0.0 <= x <= self.total_length:
                raise ValueError(
                    f"setup: {what} at {x!r} m must lie on the assembly [0, "
                    f"{self.total_length:.6g}] m"
                )
        if self.setup.clamp is not None and self.boundary == "free-free":
            raise ValueError("setup.clamp is for a clamped boundary; the specimen is free-free")

    @property
    def total_length(self) -> float:
        """Assembly length [m]."""
        return 2.0 * self.beam_length - self.overlap

    @property
    def lap_start(self) -> float:
        """X of the start of the lap (= start of beam B) [m]."""
        return self.beam_length - self.overlap

    @property
    def cone_radius(self) -> float:
        """Radius of the pressure cone at the interface, ``D_w/2 + t tan(a)`` [m]
        (docs/equations.md section 7; ``t`` the lap thickness of one beam).
        """
        a = math.radians(self.interface.cone_angle_deg)
        return 0.5 * self.washer_diameter + self.lap_thickness * math.tan(a)

    def floor(self, mode: int) -> float:
        """Linear damping ratio [-] of elastic mode ``mode`` (1: lowest): its entry of
        ``modal_damping``, else ``interface.damping_floor``.
        """
        mode = check_int("mode", mode, 1)
        md = self.modal_damping
        return md[mode - 1] if mode <= len(md) else self.interface.damping_floor

    def with_effects(
        self,
        effects: dict,
        *,
        mode: int = 1,
        calibrated_range=None,
        form: str = "modal",
        where: str = "",
    ) -> Specimen:
        """A copy carrying ``effects`` ({name: modal values}, fitted on ``mode``) in addition to
        its own (an effect already carried on that mode, or in the joint, is replaced).

        ``form="modal"``: as :class:`SpecimenEffect` entries (a correction of ``mode``'s
        curve). ``form="physical"``: as :class:`InterfaceEffect` entries in the joint, defined
        by that modal fit (``fitted_on``) until the model maps them to joint values
        (:func:`~iwan_element.models.modal.resolve_interface_effects`). ``calibrated_range``
        [m]: the amplitudes the values were fitted on; the copy's calibrated range then spans
        its own and that one. ``where``: where the physical form sits
        (:class:`InterfaceEffect`; default each effect's own).
        """
        if form not in ("modal", "physical"):
            raise ValueError(f"form must be 'modal' or 'physical', got {form!r}")
        new = tuple(
            SpecimenEffect(n, tuple(v.items()), mode, calibrated_range) for n, v in effects.items()
        )
        cr = self.calibrated_range
        if calibrated_range is not None:
            lo, hi = check_range("calibrated_range", calibrated_range)
            cr = (lo, hi) if cr is None else (min(cr[0], lo), max(cr[1], hi))
        if form == "physical":
            keep_i = tuple(e for e in self.interface_effects if e.name not in effects)
            ife = keep_i + tuple(InterfaceEffect(e.name, fitted_on=e, where=where) for e in new)
            return replace(self, interface_effects=ife, calibrated_range=cr)
        keep = tuple(e for e in self.effects if not (e.mode == mode and e.name in effects))
        return replace(self, effects=keep + new, calibrated_range=cr)

    def replace(self, **changes) -> Specimen:
        """A validated copy with fields changed; interface fields may be given by name too."""
        names = {f.name for f in fields(self)}
        inames = {f.name for f in fields(InterfaceModel)}
        unknown = set(changes) - names - inames
        if unknown:
            raise ValueError(f"unknown Specimen fields {sorted(unknown)}")
        ichanges = {k: changes.pop(k) for k in list(changes) if k in inames and k not in names}
        if ichanges:
            changes["interface"] = replace(changes.get("interface", self.interface), **ichanges)
        return replace(self, **changes)
