"""A specimen's vibration effects on one mode, as a modal force on the beams of the transient.

The specimen's vibration effects on a mode (``specimen.effects``, modal form, amplitudes at
the sensor; ``docs/vibration_effects.md``) act as a modal force: their elements
(:func:`~iwan_element.models.modal.effects.effect_stack`: ``EFFECTS[name]`` around a
zero-force element, joint values from ``modal_to_joint`` with unit modal mass in sensor
units) are driven by the sensor-scaled modal coordinate
``Y = s q``, ``q = phi^T M x``, ``s = S phi``, and apply ``-M phi F(Y) / s`` to the bodies
(an Exudyn ``ObjectGenericODE2`` on the host's coordinates,
:mod:`~iwan_element.models.simulation.host`, with its exact Jacobian ``M phi phi^T M F'(Y)``),
which the
mass-orthogonality of the modes keeps on this mode. Their work is ``(1/s^2) int F dY``.
"""

from __future__ import annotations

import numpy as np
from exudyn.itemInterface import ObjectGenericODE2
from numpy.typing import NDArray

from ..modal.effects import ZeroElement, effect_stack
from ..specimens.specimen import Specimen

__all__ = ["ModalEffects"]


class ModalEffects:
    """The specimen's effects on one mode as a modal force on the host's bodies (module
    docstring).
    """

    def __init__(self, specimen: Specimen, mode: int, L, phi, omega0: float):
        self.el, self.names = effect_stack(specimen, mode, omega0)
        self.s = float(L.S @ phi)
        self.a_free = L.M @ phi
        self.a: NDArray[np.float64] | None = None

    def attach(self, model) -> None:
        """Add the ObjectGenericODE2 on the host's node (:class:`~.host.HostModel`; the
        system must be assembled again afterwards): the row ``a = T^T M phi`` in the host's
        coordinates.
        """
        self.a = model.T.T @ self.a_free
        self.aa = np.outer(self.a, self.a)
        el, s, av = self.el, self.s, self.a

        def force(mbs_, t, item, q, q_t):
            F, _ = el.trial(s * float(av @ np.asarray(q)), s * float(av @ np.asarray(q_t)))
            return (-av * (F / s)).tolist()

        def jacobian(mbs_, t, item, q, q_t, f_q, f_v):
            F, K = el.trial(s * float(av @ np.asarray(q)), s * float(av @ np.asarray(q_t)))
            c = sum(getattr(x, "c", 0.0) for x in self._stack())
            return self.aa * (K * f_q + c * f_v)

        n = av.size
        model.mbs.AddObject(
            ObjectGenericODE2(
                nodeNumbers=[model.node],
                massMatrix=np.zeros((n, n)),
                forceUserFunction=force,
                jacobianUserFunction=jacobian,
            )
        )

    def _stack(self):
        el = self.el
        while not isinstance(el, ZeroElement):
            yield el
            el = el.inner

    def start(self, Y0: float, n: int = 400) -> float:
        """Drive the elements from rest to ``Y0`` (virgin loading, as the static release
        state); returns their work on the bodies' modal coordinate [J].
        """
        for y in np.linspace(0.0, Y0, n + 1)[1:]:
            self.el.trial(float(y), 0.0)
            self.el.commit()
        return self.el.work / self.s**2

    def commit(self, z, vz) -> None:
        """Commit at the host coordinates ``z`` and their rates ``vz``."""
        self.el.trial(self.s * float(self.a @ z), self.s * float(self.a @ vz))
        self.el.commit()

    def energy(self) -> tuple[float, float]:
        """(stored, dissipated) [J] on the bodies' modal coordinate."""
        s2 = self.s**2
        return self.el.stored_energy / s2, self.el.dissipated_energy / s2
