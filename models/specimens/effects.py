"""The vibration effects a specimen carries: in their modal form on one mode, or in the joint.

Two declarations of the same named effects (``docs/vibration_effects.md``):

* :class:`SpecimenEffect`, the modal (amplitude-domain) form: a correction of one mode's
  QSMA curve, with values in modal units at the specimen's sensor; it acts on that mode
  alone.
* :class:`InterfaceEffect`, the physical form: the effect's joint law (``EFFECTS[name]``, the
  class the loop diagnosis uses) at contact points of the lap, with joint-level values; every
  analysis of the specimen runs it (QSMA, harmonic balance, the nonlinear modes, the
  transient, on the 1-D beams and on the solid bodies), in every mode. How the joint-level
  values are shared among the points is the ``where`` rule below.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from iwan_element.base.validation import plain_fields, plain_number
from iwan_element.effects import EFFECTS

__all__ = ["SpecimenEffect", "InterfaceEffect", "check_range", "placement", "WHERE"]

#: Where an interface effect sits (:class:`InterfaceEffect`): ``"contact"``, every contact
#: point, a shared value in proportion to the point's tangential stiffness ``KT_i``;
#: ``"bolts"``, each bolt's shank, a shared value equally among the bolts and, within a
#: bolt, equally on the two contact points nearest its centre (the slip at the shank);
#: ``"bolt<k>"`` (``"bolt1"``, ``"bolt2"``, ...), one bolt's shank, numbered along the lap
#: from its start (:func:`placement`), the whole value on its two points (a pin bearing on
#: one hole); ``"under<k>"``, the contact under bolt ``k`` (the points nearer that bolt than
#: any other), shared in proportion to ``KT_i`` (a region under one bolt that slips on its
#: own).
WHERE = ("contact", "bolts")

#: Where each effect sits unless told: the pin is the bolt shank bearing on its hole.
DEFAULT_WHERE = {"pinning_stiffness": "bolts"}

#: The joint values that are shared among the points (totals over the interface, [N/m],
#: [N/m^3], [N s/m]); every other value (a clearance, an onset slip [m], a shape) is the
#: same at every point where the effect sits.
SHARED = ("k_p", "k_2", "k3", "c")


def placement(where: str) -> tuple[str, int | None]:
    """``(kind, k)`` of a placement: ``("contact", None)``, ``("bolts", None)``,
    ``("bolt", k)`` (bolt ``k``'s shank) or ``("under", k)`` (the contact under bolt ``k``),
    ``k`` 1-based along the lap. ValueError for anything else.
    """
    if where in WHERE:
        return where, None
    m = re.fullmatch(r"(bolt|under)([1-9][0-9]*)", where) if isinstance(where, str) else None
    if m is None:
        raise ValueError(
            f"where must be one of {WHERE}, 'bolt<k>' or 'under<k>' (k >= 1), got {where!r}"
        )
    return m.group(1), int(m.group(2))


def check_range(name, r) -> tuple:
    """``(low, high)`` [m] with ``0 < low < high``, finite; else ValueError naming ``name``."""
    rr = tuple(float(a) for a in r)
    if len(rr) != 2 or not (0 < rr[0] < rr[1]) or not all(map(math.isfinite, rr)):
        raise ValueError(f"{name} must be (low, high) with 0 < low < high [m], got {r!r}")
    return rr


def _modal_class(name):
    cls = EFFECTS.get(name)
    if cls is None or not cls.modal_specs:
        known = sorted(n for n, c in EFFECTS.items() if c.modal_specs)
        raise ValueError(f"name must be an effect with a modal form, one of {known}, got {name!r}")
    return cls


def _checked_values(name, values, specs) -> tuple:
    """The values as a sorted tuple of ``(name, float)`` pairs, each inside its spec's bounds,
    defaults filled in; ValueError naming the effect and the value otherwise.
    """
    want = {sp.name: sp for sp in specs}
    vals = {
        **{k: sp.default for k, sp in want.items() if sp.default is not None},
        **dict(values),
    }  # a value with a default may be left out
    if set(vals) != set(want):
        raise ValueError(f"values of {name!r} must be {sorted(want)}, got {sorted(vals)}")
    vals = {k: plain_number(v) for k, v in vals.items()}
    for k, v in vals.items():
        sp = want[k]
        if (
            isinstance(v, bool)
            or not isinstance(v, (int, float))
            or not math.isfinite(v)
            or not sp.lower <= v <= sp.upper
        ):
            raise ValueError(
                f"{name} {k} must be a finite number in [{sp.lower}, {sp.upper}] {sp.unit}, "
                f"got {v!r}"
            )
    return tuple(sorted((k, float(v)) for k, v in vals.items()))


@dataclass(frozen=True)
class SpecimenEffect:
    """A named vibration effect carried by a specimen, in its modal (amplitude-domain) form.

    Parameters
    ----------
    name : str
        A name of :data:`iwan_element.EFFECTS` with a modal form (``modal_specs``).
    values : mapping or tuple of (str, float) pairs
        The effect's modal parameters (``EFFECTS[name].modal_specs``; amplitudes in metres
        at the specimen's sensor point), each inside its declared bounds; those with a
        declared default (e.g. the ``shape`` of ``macroslip_onset``) may be left out;
        stored as a sorted tuple of pairs (hashable).
    mode : int
        Elastic mode the effect acts on (1: lowest).
    calibrated_range : tuple of 2 floats or None
        Sensor amplitudes [m] the values were fitted on.

    Notes
    -----
    The effect's modal form (``modal_form(X, f, zeta, zeta_floor, **values)``) is applied on
    top of the QSMA curve of that mode (:func:`~iwan_element.models.modal.modal_amplitude_curve`).
    """

    name: str
    values: tuple
    mode: int = 1
    calibrated_range: tuple | None = None

    def __post_init__(self):
        plain_fields(self)
        cls = _modal_class(self.name)
        object.__setattr__(self, "values", _checked_values(self.name, self.values, cls.modal_specs))
        if isinstance(self.mode, bool) or not isinstance(self.mode, int) or self.mode < 1:
            raise ValueError(f"mode must be an integer >= 1, got {self.mode!r}")
        if self.calibrated_range is not None:
            object.__setattr__(
                self, "calibrated_range", check_range("calibrated_range", self.calibrated_range)
            )

    @property
    def parameters(self) -> dict:
        """The modal parameters as a dict (SI units)."""
        return dict(self.values)


@dataclass(frozen=True)
class InterfaceEffect:
    """A named vibration effect in the joint: its law at contact points of the lap.

    Parameters
    ----------
    name : str
        A name of :data:`iwan_element.EFFECTS` with a modal form: ``pinning_stiffness``,
        ``macroslip_onset``, ``hardening``, ``viscous_damping``. Each point where it sits
        carries ``EFFECTS[name]`` wrapped around its Iwan element (the loop diagnosis's
        classes), acting on that point's tangential slip.
    values : mapping or tuple of (str, float) pairs, or None
        Joint-level values, the effect's constructor parameters (``EFFECTS[name].specs``):
        ``k_p`` [N/m] and ``delta`` [m]; ``k_2`` [N/m], ``u_s`` [m] and ``shape`` [-];
        ``k3`` [N/m^3]; ``c`` [N s/m]. A stiffness, cubic stiffness or dashpot (``k_p``,
        ``k_2``, ``k3``, ``c``) is the total over the interface, shared by the ``where``
        rule; a length (``delta``, ``u_s``) or shape is the same at every point where the
        effect sits. ``None`` when the effect is given by the modal fit it comes from
        (``fitted_on``): the model then maps and fits it
        (:func:`~iwan_element.models.modal.resolve_interface_effects`) the first time an
        analysis needs it.
    where : {"contact", "bolts", "bolt<k>", "under<k>"} or ""
        Where the effect sits (:data:`WHERE`): every contact point (shared in proportion to
        ``KT_i``), each bolt's shank (shared equally among the bolts, on the two points
        nearest each bolt's centre), bolt ``k``'s shank alone (``"bolt2"``: the second bolt
        from the lap's start) or the contact under bolt ``k`` (``"under2"``: its points,
        in proportion to ``KT_i``); a specimen with fewer bolts refuses ``k`` where it is
        used.
        Default ``""``: ``"bolts"`` for ``pinning_stiffness``,
        else ``"contact"``.
    fitted_on : SpecimenEffect or None
        The modal fit the values come from (its mode, modal values and calibrated range):
        provenance once ``values`` are set, the definition while they are ``None``.
    fit_misfit : tuple of 2 floats or None
        ``(frequency, damping)``: the largest relative misfit [-] of the physical form's QSMA
        against the modal form on ``fitted_on``'s mode over its calibrated range, left by
        the fit (``None``: not fitted).
    """

    name: str
    values: tuple | None = None
    where: str = ""
    fitted_on: SpecimenEffect | None = None
    fit_misfit: tuple | None = None

    def __post_init__(self):
        plain_fields(self)
        cls = _modal_class(self.name)
        if not self.where:
            object.__setattr__(self, "where", DEFAULT_WHERE.get(self.name, "contact"))
        placement(self.where)
        if self.fitted_on is not None:
            if not isinstance(self.fitted_on, SpecimenEffect) or self.fitted_on.name != self.name:
                raise ValueError(
                    f"fitted_on must be a SpecimenEffect of {self.name!r}, got {self.fitted_on!r}"
                )
        if self.values is None:
            if self.fitted_on is None:
                raise ValueError(f"{self.name}: give values (joint level) or fitted_on (modal)")
            return
        vals = _checked_values(self.name, self.values, cls.specs)
        if self.name == "macroslip_onset" and dict(vals)["u_s"] <= 0.0:
            raise ValueError(f"macroslip_onset u_s must be > 0 [m], got {dict(vals)['u_s']!r}")
        object.__setattr__(self, "values", vals)
        if self.fit_misfit is not None:
            fm = tuple(float(v) for v in self.fit_misfit)
            if len(fm) != 2 or not all(math.isfinite(v) and v >= 0 for v in fm):
                raise ValueError(
                    f"fit_misfit must be (frequency, damping) misfits >= 0, got {self.fit_misfit!r}"
                )
            object.__setattr__(self, "fit_misfit", fm)

    @property
    def parameters(self) -> dict:
        """The joint-level values as a dict (SI units); empty while unresolved."""
        return dict(self.values or ())

    @property
    def resolved(self) -> bool:
        """True when the joint-level values are set."""
        return self.values is not None
