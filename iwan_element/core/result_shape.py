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
* ``_repr_html_()``: the report in a notebook.

:class:`ResultShape` supplies the notebook representation and the panel count; each class
supplies the rest.
"""
from __future__ import annotations

import html
from dataclasses import dataclass
from typing import ClassVar

__all__ = ["ResultShape", "panels"]


@dataclass(frozen=True, eq=False, kw_only=True)
class ResultShape:
    """Base of the package's result classes (frozen dataclasses): the ``warnings`` field
    (keyword-only, a tuple of str, empty by default), ``plot_panels`` (how many Axes ``plot``
    draws on) and ``_repr_html_`` (the report in a notebook)."""

    plot_panels: ClassVar[int] = 1
    warnings: tuple = ()

    def _repr_html_(self) -> str:
        return f"<pre>{html.escape(self.report())}</pre>"


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
