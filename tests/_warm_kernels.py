"""Compile the package's numba kernels into their on-disk cache before the suite runs.

Every kernel is ``@njit(cache=True)``: the first process to call it with a signature compiles
it and writes the machine code beside the module (``__pycache__``); later processes load it.
In a fresh clone the cache is cold, and the xdist workers started together each compiled the
same kernels (a few seconds each) while their tests waited. ``tests/conftest.py`` runs this
script once per copy of the package the suite imports (the installed package the workers use,
and the checkout's source tree that the README recipes and the fresh-process tests import
from the repository root), before the workers start.

:func:`warm` calls every compiled entry point through the routes the package uses, with
writable and read-only arrays (numba compiles a read-only array as another signature);
``tests/test_kernel.py`` checks that afterwards every kernel of the package holds at least one
compiled signature, so a new kernel is not left out silently.

Run as a script (``python tests/_warm_kernels.py``) it warms the package that ``import
iwan_element`` finds and prints where that is.
"""

from __future__ import annotations

import numpy as np


def _readonly(a: np.ndarray) -> np.ndarray:
    b = np.array(a)
    b.setflags(write=False)
    return b


def _masing_and_periodic() -> None:
    """The reversal-stack kernel (one element, whole histories) and the periodic form."""
    from iwan_element import IwanJoint, IwanJointBank, IwanParameters
    from iwan_element.core.history import unit_params
    from iwan_element.core.masing import masing_constants, masing_history, reversal_structure
    from iwan_element.core.periodic import periodic_harmonic_jacobian, periodic_rows

    p = IwanParameters(1.0, 100.0, -0.5, 0.2)
    u = 0.02 * np.sin(np.linspace(0.0, 12.0, 400))
    IwanJoint(p).force_history(u)
    j = IwanJoint(p)
    for x in (1e-3, 3e-3, -2e-3):
        j.trial(x)
        j.commit()
    bank = IwanJointBank([p, unit_params(0.01, -0.4, 0.3)])
    for x in (1e-3, 3e-3, -2e-3):
        bank.commit(np.array([x, 0.5 * x]))
    from iwan_element.exudyn.laws.condensed import condensed_slips

    condensed_slips(bank, bank.u + 1e-4, 1e-3 * np.eye(2), ftol=1e-12)  # bank trials too
    for uu in (u, _readonly(u)):
        masing_history(uu, p)
        masing_history(np.vstack([uu, 0.5 * uu]), [p, p])
        reversal_structure(uu, 0.0, segments=True)
    C = np.array([masing_constants(p, 0.0)] * 2)
    n = 64
    th = 2.0 * np.pi * np.arange(n) / n
    U = 0.02 * np.vstack([np.cos(th), np.sin(th)])
    E = np.column_stack([np.ones(n), np.cos(th), np.sin(th)])
    P = np.linalg.pinv(E)
    for CC, UU in ((C, U), (_readonly(C), U), (C, _readonly(U))):
        _, K, A, _ = periodic_rows(CC, UU)
        periodic_harmonic_jacobian(K, A, P, E)
        periodic_harmonic_jacobian(K, A, P, E, shift=_readonly(np.ones(2)))


def _effects() -> None:
    """The effects' kernels: slider laws, slip degradation, backlash, the series solver."""
    from iwan_element import (
        AsymmetricSlip,
        Backlash,
        BreakAway,
        IwanJoint,
        IwanParameters,
        SlipDegradation,
    )
    from iwan_element.effects.engine.evaluate import Evaluator

    p = IwanParameters(1.0, 100.0, -0.5, 0.2)
    u = 0.02 * np.sin(np.linspace(0.0, 12.0, 400))
    ev = Evaluator(u, np.zeros(400), np.arange(400), np.arange(400), tol=0.0)
    for names, values in (
        (("slip_degradation", "backlash"), [{"rate": 0.5}, {"gap": 1e-3, "drag": 0.05}]),
        (("breakaway", "backlash"), [{"ratio": 1.5}, {"gap": 1e-3, "drag": 0.05}]),
    ):
        ev.unit_force((0.01, -0.5, 0.2), names, values)
    d = SlipDegradation(IwanJoint(p), rate=0.5)
    d.correction_history(u, np.linspace(0.0, 1e-3, 400))
    b = BreakAway(IwanJoint(p), ratio=1.5)
    b.correction_history(u)
    a = AsymmetricSlip(IwanJoint(p), asymmetry=0.2)
    a.force_history(u[:60])
    Backlash(d, gap=1e-3, drag=0.05).force_history(u[:50])
    Backlash(b, gap=1e-3, drag=0.05).force_history(u[:50])
    for el in (SlipDegradation(IwanJoint(p), rate=0.5), BreakAway(IwanJoint(p), ratio=1.5)):
        for x in (1e-3, 3e-3, -2e-3):
            el.trial(x)
            el.commit()


def warm() -> None:
    """Call every compiled entry point of the package once (module docstring)."""
    _masing_and_periodic()
    _effects()


if __name__ == "__main__":
    import iwan_element

    warm()
    print(iwan_element.__file__)
