"""The one shape every result object of the package has.

Every fit, curve, diagnosis, ensemble and uncertainty result offers (the contract checked by
``tests/test_api_shape.py`` on every public result class):

* ``report() -> str``: a human-readable summary, units in brackets;
* ``to_dict() -> dict``: JSON-safe (``json.dumps(..., allow_nan=False)`` works);
* ``warnings``: a tuple of str, what the data could not support;
* ``success``: bool, whether the result can be used as it stands;
* ``plot(ax=None)``: draws the result and returns the list of matplotlib artists. The axes
  contract is one for all: ``ax`` is ``None`` (a new figure with the result's
  ``plot_panels`` panels), one Axes (results with one panel) or a sequence of
  ``plot_panels`` Axes (:func:`panels`);
* ``verdict() -> str``: the report's first line, ``success`` in a tester's words: "usable"
  or "NOT usable: <reasons>" (:meth:`ResultShape.failure_reasons`);
* ``_repr_html_()``: the report in a notebook.

:class:`ResultShape` supplies the notebook representation and the panel count; each class
supplies the rest.
"""
from __future__ import annotations

import html
import itertools
from dataclasses import dataclass
from typing import ClassVar

__all__ = ["ResultShape", "panels", "table_lines"]


@dataclass(frozen=True, eq=False, kw_only=True)
class ResultShape:
    """Base of the package's result classes (frozen dataclasses): the ``warnings`` field
    (keyword-only, a tuple of str, empty by default), ``plot_panels`` (how many Axes ``plot``
    draws on) and ``_repr_html_`` (the report in a notebook)."""

    plot_panels: ClassVar[int] = 1
    warnings: tuple = ()

    def failure_reasons(self) -> tuple:
        """Why ``success`` is False, each reason in a tester's words (empty when it is True).
        The base reads the result's ``failures`` (the reasons its maker stated where it
        decided ``success``), else the warnings; a class whose verdict has its own reasons
        (a parameter the data do not identify, a misfit beyond the noise) states them."""
        if self.success:
            return ()
        return (tuple(getattr(self, "failures", ())) or tuple(self.warnings)
                or ("the result did not meet its own success rule",))

    def verdict(self) -> str:
        """One line: whether the result can be used as it stands, and if not, why."""
        reasons = self.failure_reasons()
        return "usable" if not reasons else "NOT usable: " + "; ".join(reasons)

    def _repr_html_(self) -> str:
        return f"<pre>{html.escape(self.report())}</pre>"


def table_lines(columns, rows, *, indent: int = 2) -> list[str]:
    """The lines of a fixed-width table in a report: a header, then one line per row.

    Parameters
    ----------
    columns : sequence of (str, str)
        ``(title, format spec)`` per column; the spec is Python's (``"<26"``, ``"9.4g"``,
        ``"11.4e"``), and the title takes its width and alignment (right unless the spec
        starts with ``<`` or ``^``).
    rows : iterable of sequences
        The values of each row, one per column.
    indent : int, keyword-only
        Spaces before each line.
    """
    pad = " " * indent
    heads = []
    for title, spec in columns:
        align = spec[0] if spec[:1] in ("<", ">", "^") else ">"
        width = "".join(itertools.takewhile(str.isdigit, spec.lstrip("<>^")))
        heads.append(format(title, f"{align}{width}"))
    out = [pad + " ".join(heads)]
    for row in rows:
        out.append(pad + " ".join(format(v, spec) for v, (_, spec) in zip(row, columns)))
    return out


def panels(ax, n: int, *, figsize=None, sharex: bool = False) -> list:
    """The ``n`` Axes a result draws on, from its ``ax`` argument (the contract above).

    Raises
    ------
    TypeError
        ``ax`` is neither ``None``, one Axes (``n == 1``) nor a sequence of ``n`` Axes.
    """
    if ax is None:
        import matplotlib.pyplot as plt
        _, axs = plt.subplots(n, 1, sharex=sharex, squeeze=False,
                              figsize=figsize or (6.0, 3.2 * n))
        return list(axs[:, 0])
    if hasattr(ax, "plot"):
        if n != 1:
            raise TypeError(f"ax must be None or a sequence of {n} Axes (this result draws "
                            f"{n} panels), got one Axes")
        return [ax]
    try:
        axs = list(ax)
    except TypeError:
        raise TypeError(f"ax must be None, one Axes or a sequence of {n} Axes, got "
                        f"{type(ax).__name__}") from None
    if len(axs) != n or not all(hasattr(a, "plot") for a in axs):
        raise TypeError(f"ax must be a sequence of {n} Axes for this result, got {len(axs)} "
                        "items")
    return axs
