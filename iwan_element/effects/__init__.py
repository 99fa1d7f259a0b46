"""Physical effects the four-parameter Iwan model lacks, as plug-in joint elements.

One module per effect; each holds its physics once: an element following the element
protocol (``trial``/``commit``/``revert``/``reset`` and the energy read-outs) that wraps a
joint, its parameters as :class:`ParamSpec` (bounds, unit, meaning, scaling used by the
fits), a docstring with the physics and its source, and where one exists its
amplitude-domain (modal) form used by :func:`~iwan_element.diagnose_vibration`.
:data:`EFFECTS` is filled by discovering every module of this package, so adding an effect
means adding one file that defines a subclass of the shared base (:class:`Effect`, in
:mod:`.base` with :class:`ParamSpec`) with an ``effect`` name. The machinery below and behind
the effects lives in :mod:`.engine`: the exact slider laws, the slider banks and Jenkins banks
the slider-level effects are built on, their compiled kernels, and the whole-history
evaluator the diagnoses run (:mod:`.engine.evaluate`, which reads :data:`EFFECTS`).

========================  =====================================================================
name                      physics
========================  =====================================================================
``viscous_damping``       ``F = F_j(u) + c v`` (a dashpot in parallel); modal: ``+ zeta_v``
``pinning_stiffness``     ``F = F_j(u) + k_p sign(u) max(|u| - delta, 0)``; modal: describing-
                          function stiffness of the dead-zone spring
``backlash``              a gap ``2 gap`` wide in series with the joint: the joint's history
                          frozen while it is open, crossed against a friction ``drag``
                          (default 0: at zero force)
``slip_degradation``      slider thresholds ``exp(-rate D) phi_i`` (wear with the dissipated
                          energy ``D``), stiffness unchanged
``asymmetric_slip``       slider thresholds ``(1 + a) phi_i`` forward, ``(1 - a) phi_i`` back
``breakaway``             static threshold ``r phi_i`` until a slider starts to slide, kinetic
                          ``phi_i`` while sliding (the break-away peak after each reversal)
========================  =====================================================================

Slider-level effects (the last three) wrap a plain joint directly; the others wrap anything.
Asymmetric slip and break-away are one slider law each and may wrap one another (their
thresholds multiply: :mod:`iwan_element.effects.engine.law`); slip degradation stands alone.
Every effect reduces exactly to the wrapped element at its neutral parameter values.
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil
from typing import Any

from ..core.protocol import check_element
from .asymmetric_slip import AsymmetricSlip
from .backlash import Backlash
from .base import Effect, ParamSpec
from .breakaway import BreakAway
from .hardening import Hardening
from .macroslip_onset import MacroslipOnset
from .pinning_stiffness import PinningStiffness
from .slip_degradation import SlipDegradation
from .viscous_damping import ViscousDamping

__all__ = [
    "EFFECTS",
    "Effect",
    "ParamSpec",
    "ViscousDamping",
    "PinningStiffness",
    "Backlash",
    "SlipDegradation",
    "AsymmetricSlip",
    "BreakAway",
    "Hardening",
    "MacroslipOnset",
    "make_effect",
    "base_joint",
    "register_effect",
]

EFFECTS: dict = {}
"""The effect library by name (the names users and reports refer to)."""


def register_effect(cls) -> type[Effect]:
    """Add an effect class (a subclass of the shared base with a unique ``effect`` name and
    ``specs``) to :data:`EFFECTS`; returns it, so it can be used as a decorator.
    """
    if not (inspect.isclass(cls) and issubclass(cls, Effect) and cls.effect):
        raise ValueError(f"cls must be an effect class with an 'effect' name, got {cls!r}")
    if cls.effect in EFFECTS and EFFECTS[cls.effect] is not cls:
        raise ValueError(f"an effect named {cls.effect!r} is already registered")
    EFFECTS[cls.effect] = cls
    return cls


def _discover() -> None:
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
        if info.name.startswith("_") or info.ispkg or info.name == "base":
            continue
        mod = importlib.import_module(f"{__name__}.{info.name}")
        for obj in vars(mod).values():
            if (
                inspect.isclass(obj)
                and issubclass(obj, Effect)
                and obj.effect
                and obj.__module__ == mod.__name__
            ):
                register_effect(obj)


_discover()


def make_effect(name: str, inner, **parameters: float) -> Effect:
    """Wrap ``inner`` in the effect called ``name`` with the given parameters.

    ``parameters`` must be the effect's parameter names (``EFFECTS[name].parameter_names``;
    those with a default may be left out) or its options (``EFFECTS[name].options``); unknown
    names raise ``ValueError``.
    """
    if name not in EFFECTS:
        raise ValueError(f"unknown effect {name!r}; known effects are {sorted(EFFECTS)}")
    cls = EFFECTS[name]
    unknown = set(parameters) - set(cls.parameter_names) - set(cls.options)
    if unknown:
        raise ValueError(
            f"effect {name!r} takes parameters {list(cls.parameter_names)}"
            + (f" and options {list(cls.options)}" if cls.options else "")
            + f", not {sorted(unknown)}"
        )
    missing = [s.name for s in cls.specs if s.default is None and s.name not in parameters]
    if missing:
        raise ValueError(f"effect {name!r} needs parameter(s) {missing}")
    return cls(inner, **parameters)


def base_joint(element) -> Any:
    """The innermost element below any stack of effects (``ValueError`` if ``element`` is no
    joint element).
    """
    check_element(element, name="element")
    while isinstance(element, Effect):
        element = element.inner
    return element
