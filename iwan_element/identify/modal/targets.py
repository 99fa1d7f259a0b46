"""Linear modal targets from a test: the result type shared by free decays, FRFs and sweeps.

:class:`ModalTargets` holds what a linear model update needs of a test: per mode the natural
frequency, the damping ratio, the amplitude at every sensor (a shape, compared by MAC and by
ratios) and, where the force was measured, the modal constant, each with its standard error
and a statement of where it was measured (the window of a ring-down, the amplitude range of a
sweep) and whether the structure was linear there. Made by
:func:`~iwan_element.identify.free_decay.free_decay_modes`,
:func:`~iwan_element.identify.sweeps.frf_modes.frf_modes` and
:func:`~iwan_element.identify.sweeps.frf_modes.sweep_modes` (``docs/modal_targets.md``).

Modes are numbered 1, 2, ... by ascending frequency of the identified physical poles; this is
not a model's mode number (an in-plane mode, a mode no sensor sees): pair them with a model's
modes by frequency and MAC (:func:`mac`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ...base.result_shape import ResultShape, format_value, panels, table_lines, wrap
from .mode_target import ModeTarget, mac

if TYPE_CHECKING:
    from matplotlib.artist import Artist

__all__ = ["ModalTargets"]


@dataclass(frozen=True, eq=False)
class ModalTargets(ResultShape):
    """Linear modal targets of one test (see the module docstring).

    Parameters
    ----------
    modes : sequence of ModeTarget
        By ascending frequency, indexed 1, 2, ...
    source : str
        ``"free decay"``, ``"frf"`` or ``"sweep"``.
    notes : str
        How the targets were made (filters, orders, windows).
    warnings : tuple of str
        What the data could not support.
    failures : tuple of str
        Why the targets are not usable as they stand (also among ``warnings``).

    Notes
    -----
    The views for a model update (:attr:`frequencies`, :attr:`shapes`,
    :attr:`modal_constants` and their ``*_stderr``) map the mode index to the value.
    """

    modes: tuple = ()
    source: str = ""
    notes: str = ""
    failures: tuple = ()

    def __post_init__(self):
        modes = tuple(self.modes)
        if not all(isinstance(m, ModeTarget) for m in modes):
            raise ValueError("modes must be a sequence of ModeTarget")
        if [m.index for m in modes] != list(range(1, len(modes) + 1)):
            raise ValueError("modes must be indexed 1, 2, ... in order")
        object.__setattr__(self, "modes", modes)
        self._fold_failures()

    # ---- views for the updater ---------------------------------------------------------
    @property
    def frequencies(self) -> dict:
        """``{mode index: natural frequency [Hz]}``."""
        return {m.index: m.frequency for m in self.modes}

    @property
    def frequency_stderr(self) -> dict:
        """``{mode index: standard error [Hz]}`` (:attr:`ModeTarget.frequency_stderr`)."""
        return {m.index: m.frequency_stderr for m in self.modes}

    @property
    def damping_ratios(self) -> dict:
        """``{mode index: damping ratio [-]}``."""
        return {m.index: m.damping_ratio for m in self.modes}

    @property
    def damping_ratio_stderr(self) -> dict:
        """``{mode index: standard error [-]}``."""
        return {m.index: m.damping_ratio_stderr for m in self.modes}

    @property
    def shapes(self) -> dict:
        """``{mode index: {position: signed real amplitude [m]}}``: the real part of
        :attr:`ModeTarget.shape` (modes with sensors only).
        """
        return {
            m.index: {p: float(v.real) for p, v in zip(m.positions, m.shape)}
            for m in self.modes
            if m.positions
        }

    @property
    def shape_stderr(self) -> dict:
        """``{mode index: {position: standard error of the real amplitude [m]}}``."""
        return {
            m.index: {p: float(s[0]) for p, s in zip(m.positions, m.shape_std)}
            for m in self.modes
            if m.positions
        }

    @property
    def complex_shapes(self) -> dict:
        """``{mode index: {position: complex amplitude [m]}}`` (:attr:`ModeTarget.shape`)."""
        return {
            m.index: {p: complex(v) for p, v in zip(m.positions, m.shape)}
            for m in self.modes
            if m.positions
        }

    @property
    def modal_constants(self) -> dict:
        """``{mode index: modal constant [1/kg]}`` (modes with a measured force only)."""
        return {m.index: m.modal_constant for m in self.modes if math.isfinite(m.modal_constant)}

    @property
    def modal_constant_stderr(self) -> dict:
        """``{mode index: standard error [1/kg]}``."""
        return {
            m.index: m.modal_constant_std for m in self.modes if math.isfinite(m.modal_constant)
        }

    def mac(self, index: int, shape) -> float:
        """MAC of mode ``index``'s complex shape with ``shape`` ({position: amplitude})."""
        if index not in self.complex_shapes:
            raise ValueError(
                f"index must be a mode with a shape, one of "
                f"{sorted(self.complex_shapes)}, got {index!r}"
            )
        return mac(self.complex_shapes[index], dict(shape))

    # ---- result shape --------------------------------------------------------------------
    @property
    def success(self) -> bool:
        """At least one mode and no failures."""
        return not self.failure_reasons()

    def failure_reasons(self) -> tuple:
        """Why the targets are not usable, one sentence each (empty when they are)."""
        none = () if self.modes else ("no physical mode was identified",)
        return tuple(self.failures) + none

    def to_dict(self) -> dict:
        """The targets as a dict (frequencies [Hz], damping ratios [-], mode shapes)."""
        return {
            "source": self.source,
            "notes": self.notes,
            "modes": [m.to_dict() for m in self.modes],
            "warnings": list(self.warnings),
            "failures": list(self.failures),
            "success": self.success,
        }

    def _mode_rows(self):
        return [
            (
                m.index,
                m.label,
                m.frequency,
                m.frequency_stderr,
                m.damping_ratio,
                m.damping_ratio_stderr,
                m.modal_constant if math.isfinite(m.modal_constant) else None,
                m.modal_constant_std if math.isfinite(m.modal_constant_std) else None,
                m.window[0],
                m.window[1],
                m.amplitude_range[0],
                m.amplitude_range[1],
                m.frequency_drift if math.isfinite(m.frequency_drift) else None,
                "-" if m.linear is None else ("yes" if m.linear else "no"),
            )
            for m in self.modes
        ]

    def _shape_rows(self):
        return [
            (
                m.index,
                s,
                p if not isinstance(p, tuple) else str(p),
                float(v.real),
                float(e[0]),
                float(v.imag),
                float(e[1]),
            )
            for m in self.modes
            for s, p, v, e in zip(m.sensors, m.positions, m.shape, m.shape_std)
        ]

    def _tables(self) -> list:
        out: list[tuple[str, tuple[str, ...], list]] = [
            (
                "modes",
                (
                    "mode",
                    "label",
                    "frequency [Hz]",
                    "stderr [Hz]",
                    "damping [-]",
                    "stderr [-]",
                    "modal constant [1/kg]",
                    "stderr [1/kg]",
                    "window start",
                    "window end",
                    "amplitude start [m]",
                    "amplitude end [m]",
                    "frequency drift [Hz]",
                    "linear",
                ),
                self._mode_rows(),
            )
        ]
        if any(m.positions for m in self.modes):
            out.append(
                (
                    "shapes",
                    (
                        "mode",
                        "sensor",
                        "position [m]",
                        "real [m]",
                        "stderr real [m]",
                        "imag [m]",
                        "stderr imag [m]",
                    ),
                    self._shape_rows(),
                )
            )
        out.append(
            (
                "run",
                ("quantity", "value"),
                [("source", self.source), ("modes", len(self.modes)), ("notes", self.notes)],
            )
        )
        return out

    def report(self) -> str:
        """The verdict, then one line per mode and the shapes, units in brackets."""
        lines = [self.verdict(), f"Modal targets ({self.source}), {len(self.modes)} mode(s)"]
        if self.notes:
            lines += wrap(f"  {self.notes}", indent="    ")
        lines += table_lines(
            [
                ("mode", "4d"),
                ("f [Hz]", "11.6g"),
                ("+-", "8.2g"),
                ("zeta [-]", "10.4g"),
                ("+-", "8.2g"),
                ("c [1/kg]", "9.4g"),
                ("+-", "8.2g"),
                ("window", "<19"),
                ("X [m]", "<19"),
                ("linear", "<6"),
            ],
            [
                (
                    m.index,
                    m.frequency,
                    m.frequency_stderr,
                    m.damping_ratio,
                    m.damping_ratio_stderr,
                    m.modal_constant,
                    m.modal_constant_std,
                    f"{format_value(m.window[0], 4)}-{format_value(m.window[1], 4)}",
                    f"{format_value(m.amplitude_range[0], 3)}-"
                    f"{format_value(m.amplitude_range[1], 3)}",
                    "-" if m.linear is None else ("yes" if m.linear else "no"),
                )
                for m in self.modes
            ],
        )
        if any(m.positions for m in self.modes):
            lines.append("  shapes (displacement at the window start, one phase per mode):")
            lines += table_lines(
                [
                    ("mode", "4d"),
                    ("sensor", "<8"),
                    ("x [m]", "<8"),
                    ("real [m]", "11.4e"),
                    ("+-", "9.2e"),
                    ("imag [m]", "11.4e"),
                    ("+-", "9.2e"),
                ],
                [
                    (
                        i,
                        s,
                        format_value(p, 4) if not isinstance(p, tuple) else str(p),
                        r,
                        er,
                        im,
                        ei,
                    )
                    for i, s, p, r, er, im, ei in self._shape_rows()
                ],
            )
        for w in self.warnings:
            lines += wrap(f"  warning: {w}", indent="    ")
        return "\n".join(lines)

    def plot(self, ax=None) -> list[Artist]:
        """The signed real shapes against sensor position, each scaled to its largest
        amplitude, with error bars; returns the artists. One panel.
        """
        (a,) = panels(ax, 1)
        artists = []
        for m in self.modes:
            if not m.positions or isinstance(m.positions[0], tuple):
                continue
            x = np.array(m.positions, float)
            order = np.argsort(x)
            v = m.shape.real[order]
            scale = float(np.max(np.abs(v))) or 1.0
            eb = a.errorbar(
                x[order],
                v / scale,
                yerr=m.shape_std[order, 0] / scale,
                marker="o",
                ls="-",
                label=f"mode {m.index}: {m.frequency:.5g} Hz",
            )
            artists += [eb.lines[0], *eb.lines[2]]
        if not artists:  # no shapes (an FRF fit): the frequencies with their errors
            f = [m.frequency for m in self.modes] or [0.0]
            artists += a.plot(range(1, len(f) + 1), f, "o")
            a.set_xlabel("mode")
            a.set_ylabel("frequency [Hz]")
            return artists
        a.axhline(0.0, color="0.6", lw=0.8)
        a.set_xlabel("sensor position [m]")
        a.set_ylabel("shape / largest amplitude [-]")
        a.legend(fontsize="small")
        return artists
