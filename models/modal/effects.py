"""A specimen's vibration effects on one mode as one element stack (the modal form).

The specimen's vibration effects on a mode (``specimen.effects``, modal form, amplitudes at
the sensor; ``docs/vibration_effects.md``) become one element stack (``EFFECTS[name]``
around a :class:`ZeroElement`, joint values from ``modal_to_joint`` with unit modal mass in
sensor units) driven by the sensor-scaled modal coordinate: the frequency-domain routes'
element ports read it, and the transient's modal force
(:class:`~iwan_element.models.simulation.modal_force.ModalEffects`) drives it in Exudyn.
"""

from __future__ import annotations

from typing import Any

from iwan_element.core.periodic import PeriodicForm
from iwan_element.effects import EFFECTS

from ..specimens.specimen import Specimen

__all__ = ["ZeroElement", "effect_stack"]


class ZeroElement:
    """A zero-force element following the joint element protocol (the base the modal
    effects wrap).
    """

    force = displacement = work = stored_energy = dissipated_energy = 0.0

    def trial(self, u, v=0.0) -> tuple[float, float]:
        """``(force [N], stiffness [N/m])`` at displacement ``u`` [m]: always ``(0, 0)``."""
        return 0.0, 0.0

    def commit(self) -> None:
        """Accept the last trial; returns None (no state to keep)."""

    def revert(self) -> None:
        """Discard the last trial; returns None (no state to keep)."""

    def reset(self) -> None:
        """Return to the virgin state; returns None (no state to keep)."""

    def periodic_form(self) -> PeriodicForm:
        """The zero force in the compiled periodic kernel's terms: no rows, no laws (the
        effects around it add theirs; the harmonic balance then runs the stack compiled).
        """
        return PeriodicForm()


def effect_stack(specimen: Specimen, mode: int, omega0: float) -> tuple[Any, list[str]]:
    """``(element, names)``: the specimen's effects on ``mode`` as one element stack around a
    :class:`ZeroElement` (joint values from ``modal_to_joint`` at unit modal mass in sensor
    units; ``omega0`` the stuck circular frequency [rad/s]), driven by the sensor-scaled
    modal coordinate. The transient's modal force and the frequency-domain routes' element
    ports both use it.
    """
    el = ZeroElement()
    names = []
    for e in specimen.effects:
        if e.mode == mode:
            cls = EFFECTS[e.name]
            el = cls(
                el,
                **cls.modal_to_joint(
                    e.parameters, modal_mass=1.0, slip_per_amplitude=1.0, omega0=omega0
                ),
            )
            names.append(e.name)
    return el, names
