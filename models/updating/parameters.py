"""Linear model updating of a specimen: the parameters a specimen has and their priors.

Finite-element model updating by the sensitivity method (M. I. Friswell, J. E. Mottershead,
*Finite Element Model Updating in Structural Dynamics*, Kluwer 1995; J. E. Mottershead,
M. Link, M. I. Friswell, "The sensitivity method in finite element model updating: a
tutorial", MSSP 25:2275-2296, 2011; docs/linear_update.md), on the specimen's stuck-joint
linear system ``(K = K0 + G^T diag(KT) G, M)`` (the small-amplitude limit, where a test's
low-level data are linear): :func:`updatable` lists every linear parameter a specimen has,
by group (``"material"``, ``"boundary"``, ``"attachments"``, ``"joint"``), with its nominal
value, unit and physical range (the prior of the update); :func:`with_parameters` sets them.
Their sensitivities are in :mod:`~iwan_element.models.updating.sensitivities`, the band
their ranges allow in :mod:`~iwan_element.models.updating.band`, the update in
:mod:`~iwan_element.models.updating.update`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

from ..reduced.dispatch import check_specimen
from ..solid.specimen import SolidSpecimen
from ..specimens.setups import Clamp, Setup

__all__ = ["Updatable", "GROUPS", "updatable", "parameter_value", "with_parameters"]

GROUPS = ("material", "boundary", "attachments", "joint")


#: Default physical ranges, as factors of the nominal value (when the setup gives none).
_FACTORS = {
    "youngs_modulus": (0.9, 1.1),
    "density": (0.95, 1.05),
    "stiffness_per_area": (0.1, 10.0),
    "normal_stiffness_per_area": (0.1, 10.0),
    "clamp.translational": (0.01, 100.0),
    "clamp.rotational": (0.01, 100.0),
    "shaker.stinger_stiffness": (0.1, 10.0),
    "shaker.suspension_stiffness": (0.1, 10.0),
}
_MASS_RANGE = (0.25, 4.0)  # a mass's range as factors of its nominal
#: Default half-widths of position ranges [m] (when the setup gives none): a shaker's
#: attachment is known to about half a force gauge's mounting base (12-17 mm across) and the
#: hand placement of a stinger against a drawing's position.
_OFFSETS = {"shaker.position": 0.005}
#: Ranges of values given as 0 (a mass or a suspension not known to be there).
_ZERO_RANGES = {"mass": (0.0, 0.05), "shaker.suspension_stiffness": (0.0, 2.0e4)}
_UNITS = {
    "youngs_modulus": "Pa",
    "density": "kg/m^3",
    "stiffness_per_area": "N/m^3",
    "normal_stiffness_per_area": "N/m^3",
    "clamp.translational": "N/m",
    "clamp.rotational": "N m/rad",
    "shaker.gauge_mass": "kg",
    "shaker.moving_mass": "kg",
    "shaker.stinger_stiffness": "N/m",
    "shaker.suspension_stiffness": "N/m",
    "shaker.position": "m",
}


@dataclass(frozen=True)
class Updatable:
    """One updatable linear parameter of a specimen.

    Attributes
    ----------
    name : str
        ``"youngs_modulus"``, ``"density"``, ``"stiffness_per_area"``,
        ``"normal_stiffness_per_area"``, ``"clamp.translational"``, ``"clamp.rotational"``,
        ``"mass:<name>"`` (a setup's point mass), ``"shaker.gauge_mass"``, ...
    group : str
        One of :data:`GROUPS`.
    nominal : float
        The specimen's value [``unit``].
    unit : str
    lower, upper : float
        Physical range [``unit``]: the prior of the update (``[lower, upper]`` is taken as
        the central 95 % of a log-normal prior around the nominal, or of a normal one when
        ``lower`` is 0) and the bounds of the search.
    description : str
    """

    name: str
    group: str
    nominal: float
    unit: str
    lower: float
    upper: float
    description: str = ""

    @property
    def log(self) -> bool:
        """Updated in ``ln p`` (a range away from 0) rather than in ``p``."""
        return self.lower > 0

    def to_dict(self) -> dict:
        """The fields by name (nominal and range in ``unit``)."""
        return {
            "name": self.name,
            "group": self.group,
            "nominal": self.nominal,
            "unit": self.unit,
            "lower": self.lower,
            "upper": self.upper,
            "description": self.description,
        }


def _setup(specimen) -> Setup:
    return specimen.setup


def _rows(specimen, st: Setup) -> list:
    """``[(name, group, nominal, description)]``: the updatable parameters of ``specimen``
    and its setup ``st``, by group (material, boundary, attachments, joint).
    """
    rows = [
        ("youngs_modulus", "material", specimen.youngs_modulus, "Young's modulus"),
        ("density", "material", specimen.density, "density"),
    ]
    if st.clamp is not None and specimen.boundary != "free-free":
        rows += [
            (
                "clamp.translational",
                "boundary",
                st.clamp.translational,
                "clamp's translational stiffness (axial and transverse)",
            ),
            ("clamp.rotational", "boundary", st.clamp.rotational, "clamp's rotational stiffness"),
        ]
    rows += [
        (f"mass:{m.name}", "attachments", m.mass, f"point mass at {m.position:.4g} m")
        for m in st.masses
    ]
    if st.shaker is not None:
        sh = st.shaker
        rows += [
            (
                "shaker.gauge_mass",
                "attachments",
                sh.gauge_mass,
                "mass below the force gauge's sensing element",
            ),
            (
                "shaker.moving_mass",
                "attachments",
                sh.moving_mass,
                "shaker's moving mass (armature, stinger, upper gauge)",
            ),
            (
                "shaker.stinger_stiffness",
                "attachments",
                sh.stinger_stiffness,
                "stinger's axial stiffness",
            ),
            (
                "shaker.suspension_stiffness",
                "attachments",
                sh.suspension_stiffness,
                "armature's suspension",
            ),
        ]
        if not (isinstance(specimen, SolidSpecimen) and _drives(specimen, sh)):
            # a solid's excitation row is part of its built bodies
            rows.append(
                (
                    "shaker.position",
                    "attachments",
                    sh.position,
                    "the stinger's attachment point along the axis (the drive point when the "
                    "force acts through the shaker)",
                )
            )
    itf = specimen.interface
    rows += [
        (
            "stiffness_per_area",
            "joint",
            itf.stiffness_per_area,
            "tangential stiffness per area of the stuck interface",
        ),
        (
            "normal_stiffness_per_area",
            "joint",
            itf.normal_stiffness_per_area,
            "normal contact stiffness per area",
        ),
    ]
    return rows


def updatable(specimen, *, ranges: dict | None = None) -> tuple:
    """Every updatable linear parameter of ``specimen`` (module docstring).

    Parameters
    ----------
    specimen : Specimen or SolidSpecimen
    ranges : dict, optional, keyword-only
        ``{name: (lower, upper)}`` overriding the setup's ranges and the defaults.

    Returns
    -------
    tuple of Updatable
        Material (Young's modulus, density), boundary (the setup's clamp springs, when the
        specimen is clamped and the setup declares a
        :class:`~iwan_element.models.specimens.setups.Clamp`), attachments (each point mass, the
        shaker's gauge mass, moving mass, stinger and suspension
        stiffness), joint (the tangential stiffness per area of the stuck interface, the
        normal contact stiffness per area).
    """
    check_specimen(specimen)
    st = _setup(specimen)
    given = {**dict(st.ranges), **dict(ranges or {})}
    rows = _rows(specimen, st)
    out = []
    for name, group, nom, desc in rows:
        unit = "kg" if name.startswith("mass:") else _UNITS[name]
        if name in given:
            lo, hi = (float(v) for v in given[name])
        elif name in _OFFSETS:
            lo, hi = nom - _OFFSETS[name], nom + _OFFSETS[name]
        elif nom > 0 and unit == "kg":
            lo, hi = nom * _MASS_RANGE[0], nom * _MASS_RANGE[1]
        elif nom > 0:
            lo, hi = nom * _FACTORS[name][0], nom * _FACTORS[name][1]
        else:
            lo, hi = _ZERO_RANGES["mass" if unit == "kg" else name]
        if not (0 <= lo <= nom <= hi and lo < hi):
            raise ValueError(
                f"the range of {name} must hold its nominal {nom:g} {unit}, got ({lo:g}, {hi:g})"
            )
        out.append(Updatable(name, group, float(nom), unit, lo, hi, desc))
    return tuple(out)


def parameter_value(specimen, name: str) -> float:
    """The value of the updatable parameter ``name`` of ``specimen``."""
    for u in updatable(specimen):
        if u.name == name:
            return u.nominal
    raise ValueError(
        f"name must be an updatable parameter of {specimen.name!r} "
        f"({[u.name for u in updatable(specimen)]}), got {name!r}"
    )


def _drives(specimen, sh) -> bool:
    """True when the force of ``specimen``'s test acts at the shaker ``sh``'s attachment."""
    return sh.force_at != "passive" and abs(specimen.excitation.position - sh.position) < 1e-9


def with_parameters(specimen, values: dict) -> Any:
    """A copy of ``specimen`` with the updatable parameters ``values`` ({name: value}) set
    (the same type: a solid keeps its bodies, scaled for the material).

    ``shaker.position`` moves the shaker's gauge mass and stinger and, when the test's force
    acts through the shaker (``force_at`` ``"gauge"`` or ``"armature"``) and the
    specimen's excitation point is the shaker's, the excitation point with it: the drive
    point is where the stinger is attached. The sensor stays where it is (an accelerometer
    on the other face is placed on its own).
    """
    changes: dict[str, Any] = {}  # the specimen's fields: values, or a new setup
    st = _setup(specimen)
    masses = {m.name: m for m in st.masses}
    sh, cl = st.shaker, st.clamp
    for name, v in values.items():
        v = float(v)
        if name in ("youngs_modulus", "density", "stiffness_per_area", "normal_stiffness_per_area"):
            changes[name] = v
        elif name.startswith("mass:") and name[5:] in masses:
            masses[name[5:]] = replace(masses[name[5:]], mass=v)
        elif name.startswith("shaker.") and sh is not None:
            if name == "shaker.position" and _drives(specimen, sh):
                changes["excitation"] = replace(specimen.excitation, position=v)
            shaker_change: dict[str, Any] = {name[7:]: v}  # one of its numeric fields
            sh = replace(sh, **shaker_change)
        elif name.startswith("clamp.") and cl is not None:
            cl = Clamp(
                **{**{"translational": cl.translational, "rotational": cl.rotational}, name[6:]: v}
            )
        else:
            raise ValueError(f"values: {name!r} is not an updatable parameter of {specimen.name!r}")
    new_setup = replace(st, masses=tuple(masses.values()), shaker=sh, clamp=cl)
    if new_setup != st:
        changes["setup"] = new_setup
    return specimen.replace(**changes) if changes else specimen
