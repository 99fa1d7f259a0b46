"""The element protocol every joint model in this package follows.

A joint element is a history-dependent force law in the style of an OpenSees uniaxial
material. Evaluation never commits: a solver may call :meth:`trial` many times per step
(Newton iterations, finite-difference Jacobians, Runge-Kutta stages, rejected steps) and
calls :meth:`commit` once per accepted step.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

__all__ = ["JointElement", "CommittedState", "check_element"]


@runtime_checkable
class JointElement(Protocol):
    """Structural type of a joint element.

    Methods
    -------
    trial(u, v=0.0) -> (force [N], stiffness [N/m])
        Evaluate at displacement ``u`` [m] and velocity ``v`` [m/s]; changes no committed state.
    commit()
        Accept the last trial.
    revert()
        Discard the last trial.
    reset()
        Return to the virgin state; energy counters to zero.

    Attributes (read-only, committed state)
    ---------------------------------------
    work, stored_energy, dissipated_energy : float
        Energies [J] since the last reset; ``work = stored_energy + dissipated_energy``.
    force, displacement : float
        Committed force [N] and displacement [m].
    """

    def trial(self, u: float, v: float = 0.0) -> tuple[float, float]:
        """Trial force [N] and tangent [N/m] at ``u`` [m], ``v`` [m/s]; commits nothing."""
        ...

    def commit(self) -> None:
        """Accept the last trial as the committed state; returns nothing."""
        ...

    def revert(self) -> None:
        """Discard the last trial, keeping the committed state; returns nothing."""
        ...

    def reset(self) -> None:
        """Return to the virgin state with the energy counters at 0 J; returns nothing."""
        ...

    @property
    def work(self) -> float:
        """Work done on the element since the last reset [J] (committed)."""
        ...

    @property
    def stored_energy(self) -> float:
        """Recoverable energy since the last reset [J] (committed)."""
        ...

    @property
    def dissipated_energy(self) -> float:
        """Energy dissipated since the last reset [J] (committed)."""
        ...

    @property
    def force(self) -> float:
        """Committed force [N]."""
        ...

    @property
    def displacement(self) -> float:
        """Committed displacement [m]."""
        ...


_PROTOCOL = (
    "trial",
    "commit",
    "revert",
    "reset",
    "work",
    "stored_energy",
    "dissipated_energy",
    "force",
    "displacement",
)


def check_element(obj, *, name: str = "obj") -> None:
    """Raise ``ValueError`` naming ``name`` unless ``obj`` follows :class:`JointElement`."""
    missing = [m for m in _PROTOCOL if not hasattr(obj, m)]
    if missing:
        raise ValueError(
            f"{name} must follow the joint element protocol (trial, commit, revert, "
            f"reset, force, displacement and energy read-outs); "
            f"{type(obj).__name__} lacks {missing}"
        )


class CommittedState:
    """Read-outs of an element's committed state, from its attributes ``_u`` [m], ``_F``
    [N], ``_W`` (work) and ``_D`` (dissipated energy) [J]: the one implementation of the
    protocol's properties for the package's elements (an element with another stored energy
    overrides :attr:`stored_energy`).
    """

    __slots__ = ()

    # set by each element (annotations only: no slot, no default)
    _u: float
    _F: float
    _W: float
    _D: float

    @property
    def displacement(self) -> float:
        """Committed displacement [m]."""
        return self._u

    @property
    def force(self) -> float:
        """Committed force [N]."""
        return self._F

    @property
    def work(self) -> float:
        """Work done on the element since the last reset, ``int F du`` [J] (committed)."""
        return self._W

    @property
    def dissipated_energy(self) -> float:
        """Energy dissipated since the last reset [J] (committed, never decreases)."""
        return self._D

    @property
    def stored_energy(self) -> float:
        """Recoverable energy [J] (committed): work minus dissipation."""
        return self._W - self._D
