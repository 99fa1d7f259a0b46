"""The energy balance of a run (:meth:`.energy.EnergyRecorder.balance`): each energy term
over the accepted steps, the total that stays constant when balanced, its error relative to
the joints' own energy, the verdict, report, tables and plot.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..base.result_shape import ResultShape, panels, table_lines, wrap

__all__ = ["EnergyBalance", "BALANCE_TOLERANCE"]

#: Largest balance error, relative to the joints' own energy, of a usable run.
BALANCE_TOLERANCE = 1e-3


@dataclass(frozen=True, eq=False, kw_only=True)
class EnergyBalance(ResultShape):
    """Energies of a run [J] at the accepted steps (from :meth:`.energy.EnergyRecorder.balance`).

    Attributes
    ----------
    t : ndarray
        Times [s].
    kinetic : ndarray
        Kinetic energy of the bodies [J].
    elastic : ndarray
        Strain energy of reduced flexible bodies, potential energy of the springs Exudyn
        reports it for, and of an interface's own linear springs [J].
    internal_work : ndarray
        Work into the internal forces of beams and generic ODE2 bodies (their strain energy
        and internal damping together) since the first step [J].
    damper_dissipation : ndarray
        Energy dissipated by the model's dampers (spring-dampers, modal damping of reduced
        bodies) since the first step [J].
    connector_work : ndarray
        Work into the connectors that report no potential energy (the user's own force
        functions: stored and dissipated together) since the first step [J].
    joint_stored, joint_dissipated : ndarray
        The Iwan joints' stored and dissipated energy (dashpots in parallel included) [J].
    external_work : ndarray
        Work of the loads since the first step [J].
    not_booked : tuple of str
        Energies the balance cannot book (named); the balance is then not usable.
    notes : tuple of str
        What the solver settings say about the balance (numerical damping).
    tolerance : float
        Largest relative error [-] of a usable balance.
    """

    t: np.ndarray
    kinetic: np.ndarray
    elastic: np.ndarray
    internal_work: np.ndarray
    damper_dissipation: np.ndarray
    connector_work: np.ndarray
    joint_stored: np.ndarray
    joint_dissipated: np.ndarray
    external_work: np.ndarray
    not_booked: tuple = ()
    notes: tuple = ()
    tolerance: float = BALANCE_TOLERANCE

    _PARTS = (
        "kinetic",
        "elastic",
        "internal_work",
        "damper_dissipation",
        "connector_work",
        "joint_stored",
        "joint_dissipated",
        "external_work",
    )

    @property
    def total(self) -> np.ndarray:
        """Energy held or dissipated minus the external work [J] (constant when balanced)."""
        return (
            self.kinetic
            + self.elastic
            + self.internal_work
            + self.damper_dissipation
            + self.connector_work
            + self.joint_stored
            + self.joint_dissipated
            - self.external_work
        )

    @property
    def scale(self) -> float:
        """The joints' own energy [J], the basis of the error: the largest, over the run,
        of their total work (stored + dissipated) and of their dissipation.
        """
        w = self.joint_stored + self.joint_dissipated
        return float(max(np.max(np.abs(w)), np.max(np.abs(self.joint_dissipated))))

    @property
    def energy_level(self) -> float:
        """The model's largest energy [J] (for comparison; not the basis of the error)."""
        return float(max(np.max(np.abs(getattr(self, p))) for p in self._PARTS))

    def error(self) -> np.ndarray:
        """Balance error over time [-]: ``(total - total[0]) / scale`` (``inf`` where the
        joints did no work but the balance moved).
        """
        d = self.total - self.total[0]
        if self.scale > 0:
            return d / self.scale
        return np.where(d == 0.0, 0.0, np.inf)

    @property
    def max_error(self) -> float:
        """Largest relative balance error [-]."""
        return float(np.max(np.abs(self.error())))

    @property
    def success(self) -> bool:
        """True when every energy is booked and the balance closes within ``tolerance``
        of the joints' own energy.
        """
        return bool(not self.not_booked and self.scale > 0 and self.max_error <= self.tolerance)

    def failure_reasons(self) -> tuple:
        """Why the balance fails, one sentence each (empty when it holds)."""
        if self.success:
            return ()
        out = []
        if self.not_booked:
            out.append("not booked: " + "; ".join(self.not_booked))
        if self.scale == 0:
            out.append(
                "the joints did no work: there is no energy of theirs to judge the balance against"
            )
        elif self.max_error > self.tolerance:
            out.append(
                f"the balance is off by {self.max_error:.2e} of the joints' own energy "
                f"({self.scale:.4g} J; tolerance {self.tolerance:.0e}): "
                + (
                    "; ".join(self.notes)
                    if self.notes
                    else "the step is too large (the error falls with its square)"
                )
            )
        return tuple(out)

    def _final(self) -> dict:
        return {p: float(getattr(self, p)[-1]) for p in self._PARTS}

    def _tables(self) -> list:
        cols = ("t [s]",) + tuple(f"{p} [J]" for p in self._PARTS) + ("error [-]",)
        history = (
            "energies over time",
            cols,
            list(
                zip(
                    *(
                        map(float, a)
                        for a in (
                            (self.t,)
                            + tuple(getattr(self, p) for p in self._PARTS)
                            + (self.error(),)
                        )
                    )
                )
            ),
        )
        rows = [(k.replace("_", " "), "J", v) for k, v in self._final().items()]
        stats = [
            ("steps", "-", len(self.t)),
            ("joints' own energy (scale)", "J", self.scale),
            ("model's energy level", "J", self.energy_level),
            ("largest balance error", "-", self.max_error),
            ("tolerance", "-", self.tolerance),
        ]
        return [
            history,
            ("energies at the end", ("quantity", "unit", "value"), rows),
            ("balance", ("quantity", "unit", "value"), stats),
        ]

    def report(self) -> str:
        """Plain-text energy balance: the verdict, then each term's final value [J]."""
        lines = [
            self.verdict(),
            f"Energy balance over {len(self.t)} steps, t = {self.t[0]:.4g} to {self.t[-1]:.4g} s",
        ]
        always = ("kinetic", "joint_stored", "joint_dissipated", "external_work")
        small = 1e-9 * self.energy_level  # the terms this model has
        rows = [
            (k.replace("_", " "), v)
            for k, v in self._final().items()
            if k in always or np.max(np.abs(getattr(self, k))) > small
        ]
        lines += table_lines([("at the end", "<20"), ("[J]", "12.5g")], rows)
        lines.append(
            f"  largest balance error {self.max_error:.2e} [-] of the joints' own "
            f"{self.scale:.4g} J (tolerance {self.tolerance:.0e}; the model holds up "
            f"to {self.energy_level:.4g} J)"
        )
        for text in self.not_booked:
            lines += wrap(f"  not booked: {text}", indent="    ")
        for text in self.notes + tuple(self.warnings):
            lines += wrap(f"  note: {text}", indent="    ")
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """The balance as a dict (errors [-], energies [J])."""
        return {
            "success": self.success,
            "max_error": self.max_error,
            "scale": self.scale,
            "energy_level": self.energy_level,
            "tolerance": self.tolerance,
            "n_steps": len(self.t),
            "final": self._final(),
            "not_booked": list(self.not_booked),
            "notes": list(self.notes),
            "warnings": list(self.warnings),
        }

    def plot(self, ax=None) -> list:
        """Draw each energy term [J] against time [s] on ``ax``; return the artists."""
        (a,) = panels(ax, 1)
        out = []
        for name in self._PARTS:
            if np.any(getattr(self, name)):
                out += a.plot(self.t, getattr(self, name), label=name.replace("_", " "))
        out += a.plot(self.t, self.total, "k--", label="balance")
        a.set_xlabel("t [s]")
        a.set_ylabel("energy [J]")
        a.legend(fontsize="small")
        return out
