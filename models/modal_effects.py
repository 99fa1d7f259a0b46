"""A specimen's vibration effects on one mode, as a modal force on the beams of the transient.

The specimen's vibration effects on a mode (``specimen.effects``, modal form, amplitudes at
the sensor; ``docs/vibration_effects.md``) act as a modal force: their elements
(``EFFECTS[name]`` around a zero-force element, joint values from ``modal_to_joint`` with
unit modal mass in sensor units) are driven by the sensor-scaled modal coordinate
``Y = s q``, ``q = phi^T M x``, ``s = S phi``, and apply ``-M phi F(Y) / s`` to the beams
(an Exudyn ``ObjectGenericODE2`` with its exact Jacobian ``M phi phi^T M F'(Y)``), which the
mass-orthogonality of the modes keeps on this mode. Their work is ``(1/s^2) int F dY``.
"""
from __future__ import annotations

import numpy as np
from exudyn.itemInterface import ObjectGenericODE2

from iwan_element.effects import EFFECTS

from .specimens import Specimen

__all__ = ["ZeroElement", "ModalEffects"]


class ZeroElement:
    """A zero-force element following the joint element protocol (the base the modal
    effects wrap)."""

    force = displacement = work = stored_energy = dissipated_energy = 0.0

    def trial(self, u, v=0.0):
        return 0.0, 0.0

    def commit(self):
        pass

    def revert(self):
        pass

    def reset(self):
        pass


class ModalEffects:
    """The specimen's effects on one mode as a modal force on the beams (module docstring)."""

    def __init__(self, specimen: Specimen, mode: int, L, phi, omega0: float):
        el = ZeroElement()
        self.names = []
        for e in specimen.effects:
            if e.mode == mode:
                cls = EFFECTS[e.name]
                el = cls(el, **cls.modal_to_joint(e.parameters, modal_mass=1.0,
                                                  slip_per_amplitude=1.0, omega0=omega0))
                self.names.append(e.name)
        self.el = el
        self.s = float(L.S @ phi)
        self.a_free = L.M @ phi
        self.free = L.free

    def attach(self, mbs, nodes, n_coordinates: int):
        """Add the ObjectGenericODE2 on ``nodes`` (4 ODE2 coordinates each)."""
        idx = np.concatenate([np.arange(mbs.GetNodeODE2Index(n), mbs.GetNodeODE2Index(n) + 4)
                              for n in nodes])
        a = np.zeros(n_coordinates)
        a[self.free] = self.a_free
        self.a = a[idx]
        self.aa = np.outer(self.a, self.a)
        el, s, av = self.el, self.s, self.a

        def force(mbs_, t, item, q, q_t):
            F, _ = el.trial(s * float(av @ np.asarray(q)), s * float(av @ np.asarray(q_t)))
            return (-av * (F / s)).tolist()

        def jacobian(mbs_, t, item, q, q_t, f_q, f_v):
            F, K = el.trial(s * float(av @ np.asarray(q)), s * float(av @ np.asarray(q_t)))
            c = sum(getattr(x, "c", 0.0) for x in self._stack())
            return self.aa * (K * f_q + c * f_v)

        n = idx.size
        mbs.AddObject(ObjectGenericODE2(nodeNumbers=list(nodes), massMatrix=np.zeros((n, n)),
                                        forceUserFunction=force, jacobianUserFunction=jacobian))

    def _stack(self):
        el = self.el
        while not isinstance(el, ZeroElement):
            yield el
            el = el.inner

    def start(self, Y0: float, n: int = 400) -> float:
        """Drive the elements from rest to ``Y0`` (virgin loading, as the static release
        state); returns their work on the beams' modal coordinate [J]."""
        for y in np.linspace(0.0, Y0, n + 1)[1:]:
            self.el.trial(float(y), 0.0)
            self.el.commit()
        return self.el.work / self.s ** 2

    def commit(self, x_free, v_free):
        self.el.trial(self.s * float(self.a_free @ x_free), self.s * float(self.a_free @ v_free))
        self.el.commit()

    def energy(self) -> tuple[float, float]:
        """(stored, dissipated) [J] on the beams' modal coordinate."""
        s2 = self.s ** 2
        return self.el.stored_energy / s2, self.el.dissipated_energy / s2
