"""A specimen's interface effects at its contact points: one law per point, every route.

Each :class:`~iwan_element.models.specimens.effects.InterfaceEffect` (joint-level values) is
shared among the contact points where it sits
(:data:`~iwan_element.models.specimens.effects.WHERE`): a stiffness, cubic stiffness or
dashpot (``k_p``, ``k_2``, ``k3``, ``c``) in proportion to the weights ``w_i`` (``KT_i /
sum KT`` over every contact point, or equal shares on the two points nearest each bolt's
centre), a length or shape the same at each of them.
Point ``i`` then carries ``EFFECTS[name]`` with those values, stacked in the order the
specimen declares them. :class:`InterfaceLaws` gives that one law to every route:

* QSMA: the virgin (backbone) force and tangent of each point's effects
  (:meth:`InterfaceLaws.backbone`) beside its Iwan backbone in the static solve, and their
  energy per cycle at each point's slip amplitude (:meth:`InterfaceLaws.dissipation`: the
  Masing rows' exact loop, the history-free laws' ``oint f du`` at the mode's frequency);
* harmonic balance and the nonlinear modes: each point's stack as a
  :class:`~iwan_element.core.periodic.PeriodicForm` beside its Iwan joint (compiled, exact
  Jacobian; :meth:`InterfaceLaws.forms`);
* the transient (1-D beams and solid bodies alike): each point's stack around its
  :class:`~iwan_element.IwanJoint` (:meth:`InterfaceLaws.elements`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np

from iwan_element import IwanJoint
from iwan_element.core.masing import masing_rows
from iwan_element.core.periodic import periodic_rows
from iwan_element.effects import EFFECTS
from iwan_element.effects.macroslip_onset import SPAN, patch_cumulative

from ..reduced.dispatch import bolt_groups, contact_points
from ..solid.specimen import SolidSpecimen
from ..specimens.effects import SHARED, InterfaceEffect, placement
from ..specimens.specimen import Specimen
from .effects import ZeroElement

__all__ = ["InterfaceLaws", "interface_laws", "point_weights", "stiffness_cap", "CYCLE_SAMPLES"]

#: Samples per cycle of the energy per cycle of a point's effects (:meth:`InterfaceLaws.
#: dissipation`): the Masing rows' loop is exact at its reversals (two per cycle, both
#: sampled), the dashpot's ``oint c v du`` is exact for a harmonic slip at any count >= 3.
CYCLE_SAMPLES = 64


def point_weights(specimen: Specimen | SolidSpecimen, effect: InterfaceEffect) -> np.ndarray:
    """Share of ``effect``'s shared value at each contact point [-], shape (n_points,), sum 1
    (module docstring): ``KT_i / sum KT`` (``"contact"``), ``1 / (2 n_bolts)`` on the two
    points nearest each bolt's centre (``"bolts"``; on a solid its patches' ``x`` elements,
    the slip along the beam, :func:`~iwan_element.models.reduced.dispatch.bolt_groups`),
    ``1/2`` on bolt ``k``'s two (``"bolt<k>"``) or ``KT_i`` over the sum of bolt ``k``'s
    group (``"under<k>"``). ValueError when the specimen has no bolt ``k``.
    """
    pts = contact_points(specimen)
    if effect.where == "contact":
        return pts.KT / pts.KT.sum()
    w = np.zeros(len(pts))
    xb = specimen.lap_start + np.asarray(specimen.bolt_positions)
    kind, k = placement(effect.where)
    if k is not None and k > xb.size:
        raise ValueError(
            f"{effect.name}: where={effect.where!r}, but the specimen has {xb.size} bolt(s)"
        )
    chosen = []
    for _, idx in bolt_groups(specimen):
        idx = np.asarray(idx)
        kb = int(np.argmin(np.abs(xb - pts.x[idx].mean())))  # the group's bolt
        if k is None or kb == k - 1:
            chosen.append(
                idx
                if kind == "under"
                else idx[np.argsort(np.abs(pts.x[idx] - xb[kb]), kind="stable")[:2]]
            )
    if not chosen:
        raise ValueError(f"{effect.name}: no contact point near bolt {k}")
    if kind == "under":
        w[chosen[0]] = pts.KT[chosen[0]] / pts.KT[chosen[0]].sum()
        return w
    for near in chosen:
        w[near] += 1.0 / (near.size * len(chosen))
    return w


def _point_values(effect: InterfaceEffect, weight: float) -> dict:
    """The constructor values of ``effect`` at a point of share ``weight`` (module
    docstring); a macroslip onset's bank reaches ``SPAN`` times its onset (as its modal
    form's joint form).
    """
    vals = {k: (v * weight if k in SHARED else v) for k, v in effect.parameters.items()}
    if effect.name == "macroslip_onset":
        vals["u_e"] = SPAN * vals["u_s"]
    return vals


def _check_patch(effect: InterfaceEffect, vals: dict, KT: float, x: float) -> None:
    """ValueError when a macroslip-onset patch at a contact point holds more stiffness (its
    bank's total, ``k_2`` times :func:`_held_per_k2`) than the point's stuck stiffness
    ``KT`` [N/m]: the patch replaces part of the stuck stiffness it sits in (``F = F_j + P -
    k_P u``), so beyond it the sliding point's tangent turns negative, a point that gives way
    under load.
    """
    if effect.name != "macroslip_onset":
        return
    held = vals["k_2"] * _held_per_k2(vals["shape"])
    if held > KT:
        raise ValueError(
            f"macroslip_onset at {effect.where}: its patch holds {held:.3g} N/m at the contact "
            f"point at x = {x:.4g} m, more than the point's stuck stiffness {KT:.3g} N/m (a "
            "patch replaces part of the stiffness it sits in): lower k_2 or spread it wider"
        )


def stiffness_cap(specimen: Specimen | SolidSpecimen, effect: InterfaceEffect) -> float:
    """The largest shared ``k_2`` [N/m] a macroslip-onset patch may have where ``effect``
    sits (its bank at no point holding more than the point's stuck stiffness,
    :func:`_check_patch`); ``inf`` for every other effect.
    """
    if effect.name != "macroslip_onset":
        return math.inf
    fit = effect.fitted_on
    values = fit.parameters if fit is not None and not effect.resolved else effect.parameters
    w = point_weights(specimen, effect)
    on = w > 0
    held = _held_per_k2(float(values.get("shape", 0.0)))
    return float(np.min(contact_points(specimen).KT[on] / (w[on] * held)))


def _held_per_k2(shape: float) -> float:
    """A macroslip-onset bank's total stiffness per unit ``k_2`` [-]: its cumulative
    fraction at ``u_e = SPAN u_s`` (:func:`_point_values`), whatever the onset.
    """
    return float(patch_cumulative(SPAN, 1.0, shape))


@dataclass(frozen=True, eq=False)
class InterfaceLaws:
    """The interface effects of a specimen at its contact points (module docstring).

    Attributes
    ----------
    stacks : tuple of tuple of (str, dict)
        Per contact point, the effects it carries (name, constructor values), innermost first;
        empty for a point without effects.
    names : tuple of str
        The effects, in the specimen's order.
    """

    stacks: tuple
    names: tuple
    parts: tuple = field(init=False, repr=False)

    def __post_init__(self):
        object.__setattr__(self, "parts", self._parts())

    def __len__(self) -> int:
        return len(self.stacks)

    def stack(self, i: int, inner) -> Any:
        """Point ``i``'s effects wrapped around the element ``inner``."""
        el = inner
        for name, vals in self.stacks[i]:
            el = EFFECTS[name](el, **vals)
        return el

    def forms(self) -> tuple:
        """Per point, its effects' :class:`~iwan_element.core.periodic.PeriodicForm` (around a
        zero force), or None for a point without effects.
        """
        return tuple(
            self.stack(i, ZeroElement()).periodic_form() if s else None
            for i, s in enumerate(self.stacks)
        )

    def elements(self, params) -> list:
        """Per point, the Iwan joint of ``params[i]`` with its effects around it (the
        transient's per-point law).
        """
        return [self.stack(i, IwanJoint(p)) for i, p in enumerate(params)]

    def _parts(self):
        """``(C, owner, shift, laws)``: every point's Masing rows stacked with the point
        each belongs to, each point's shift [N/m], and its history-free laws
        ``(point, law)``.
        """
        rows, owner, laws = [], [], []
        shift = np.zeros(len(self))
        for i, f in enumerate(self.forms()):
            if f is None:
                continue
            if f.constants.shape[0]:
                rows.append(f.constants)
                owner.append(np.full(f.constants.shape[0], i))
            shift[i] = f.shift
            laws += [(i, law) for law in f.laws]
        C = np.vstack(rows) if rows else np.empty((0, 15))
        return C, (np.concatenate(owner) if owner else np.empty(0, int)), shift, tuple(laws)

    def backbone(self, u) -> tuple[np.ndarray, np.ndarray]:
        """Virgin force [N] and tangent [N/m] of every point's effects at slips ``u`` [m]
        (any shape, the last axis the points), from rest at zero velocity.
        """
        C, owner, shift, laws = self.parts
        u = np.asarray(u, float)
        flat = u.reshape(-1, len(self))
        F = -shift * flat
        K = np.broadcast_to(-shift, flat.shape).copy()
        if owner.size:
            n = flat.shape[0]
            Ur = flat[:, owner].reshape(-1, 1)
            Fr, Kr, _, _ = masing_rows(np.tile(C, (n, 1)), Ur)
            for j in range(n):
                F[j] += np.bincount(owner, Fr[j * owner.size : (j + 1) * owner.size, 0], len(self))
                K[j] += np.bincount(owner, Kr[j * owner.size : (j + 1) * owner.size, 0], len(self))
        zero = np.zeros(flat.shape[0])
        for i, law in laws:
            f, fu, _ = law(flat[:, i], zero)
            F[:, i] += f
            K[:, i] += fu
        return F.reshape(u.shape), K.reshape(u.shape)

    def dissipation(self, amplitude, omega) -> np.ndarray:
        """Energy [J] every point's effects dissipate over one cycle of a harmonic slip of
        amplitude ``amplitude`` [m] (shape (n, n_points)) at ``omega`` [rad/s] (shape (n,)):
        the Masing rows' exact steady loop
        (:func:`~iwan_element.core.periodic.periodic_rows`) and the laws' ``oint f du``
        (``u = U cos(tau)``, ``v = -omega U sin(tau)``; :data:`CYCLE_SAMPLES` samples).
        """
        C, owner, _, laws = self.parts
        U = np.asarray(amplitude, float)
        w = np.asarray(omega, float).reshape(-1, 1)
        D = np.zeros(U.shape)
        tau = 2 * math.pi * np.arange(CYCLE_SAMPLES) / CYCLE_SAMPLES
        c, s = np.cos(tau), np.sin(tau)
        if owner.size:
            n = U.shape[0]
            paths = U[:, owner].reshape(-1, 1) * c[None, :]
            _, _, _, Dr = periodic_rows(np.tile(C, (n, 1)), paths)
            for j in range(n):
                D[j] += np.bincount(owner, Dr[j * owner.size : (j + 1) * owner.size], len(self))
        for i, law in laws:
            u = U[:, i : i + 1] * c[None, :]
            v = -w * U[:, i : i + 1] * s[None, :]
            f = law(u, v)[0]
            D[:, i] += np.sum(f * (-U[:, i : i + 1] * s[None, :]), axis=1) * (
                2 * math.pi / CYCLE_SAMPLES
            )
        return D


def interface_laws(specimen: Specimen | SolidSpecimen) -> InterfaceLaws | None:
    """The specimen's interface effects at its contact points, or None when it carries none.
    Every effect must have its joint-level values (ValueError naming the unresolved ones:
    :func:`~iwan_element.models.modal.resolve_interface_effects` maps a modal fit first).
    """
    return _laws(specimen) if specimen.interface_effects else None


@lru_cache(maxsize=32)
def _laws(specimen) -> InterfaceLaws:
    bad = [e.name for e in specimen.interface_effects if not e.resolved]
    if bad:
        raise ValueError(
            f"interface_effects {bad} have no joint values yet: map their modal fit with "
            "models.resolve_interface_effects(specimen)"
        )
    pts = contact_points(specimen)
    stacks: list[list] = [[] for _ in range(len(pts))]
    for e in specimen.interface_effects:
        w = point_weights(specimen, e)
        for i in np.flatnonzero(w > 0):
            vals = _point_values(e, float(w[i]))
            _check_patch(e, vals, float(pts.KT[i]), float(pts.x[i]))
            stacks[i].append((e.name, vals))
    return InterfaceLaws(
        stacks=tuple(tuple(s) for s in stacks),
        names=tuple(e.name for e in specimen.interface_effects),
    )
