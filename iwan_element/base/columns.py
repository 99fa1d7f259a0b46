"""Column and quantity titles of the result tables: one style, ``name [unit]``, SI units,
``[-]`` for dimensionless numbers and ``[%]`` where the value is shown in percent; counts
and labels (samples, modes, seeds) have no unit.

:func:`column` writes a title; :data:`QUANTITIES` holds the titles of the quantities that
several results put in their tables (their ``to_dict`` keys), so that a residual norm or a
wall time reads the same in every table; a result class adds its own in its ``COLUMNS``
(:class:`~iwan_element.base.result_shape.ResultShape`).
"""

from __future__ import annotations

__all__ = ["column", "unit_label", "QUANTITIES", "title_of"]


def unit_label(unit) -> str:
    """A unit as reports print it: ``"-"`` for dimensionless (``""``, ``"1"``, ``"-"``)."""
    unit = "" if unit is None else str(unit).strip("[] ")
    return "-" if unit in ("", "1", "-") else unit


def column(name: str, unit=None) -> str:
    """The title of a table column or quantity: ``"name [unit]"`` (``"amplitude [m]"``,
    ``"damping_ratio [-]"``, ``"NRMSE [%]"``); ``name`` alone when ``unit`` is ``None``
    (text, labels, flags).
    """
    return str(name) if unit is None else f"{name} [{unit_label(unit)}]"


#: ``{to_dict key: (title, unit, scale)}``: how tables title a quantity several results
#: share, and the factor from the stored value to the shown one (100 for a fraction shown
#: in %). ``unit`` ``None`` for text and flags.
QUANTITIES = {
    "wall_time": ("wall time", "s", 1.0),
    "seconds": ("time", "s", 1.0),
    "duration": ("duration", "s", 1.0),
    "t": ("t", "s", 1.0),
    "time": ("time", "s", 1.0),
    "frequency": ("frequency", "Hz", 1.0),
    "amplitude": ("amplitude", "m", 1.0),
    "force": ("force", "N", 1.0),
    "u": ("displacement", "m", 1.0),
    "phase": ("phase", "rad", 1.0),
    "damping_ratio": ("damping_ratio", "-", 1.0),
    "residual_norm": ("residual norm", "N", 1.0),
    "nrmse": ("NRMSE", "%", 100.0),
    "error_before": ("NRMSE before", "%", 100.0),
    "error_after": ("NRMSE after", "%", 100.0),
    "band_before": ("misfit band before", "N", 1.0),
    "band_after": ("misfit band after", "N", 1.0),
    "band_own": ("own misfit band", "N", 1.0),
    "band_pred": ("predicted misfit band", "N", 1.0),
    "band_campaign": ("campaign misfit band", "N", 1.0),
    "band_ratio": ("misfit band ratio", "-", 1.0),
    "ratio": ("ratio", "-", 1.0),
    "force_offset": ("force offset", "N", 1.0),
    "noise_sigma": ("noise sigma", "N", 1.0),
    "noise_level": ("noise NRMSE", "%", 100.0),
    "misfit": ("misfit beyond the noise", None, 1.0),
    "nfev": ("model evaluations", None, 1.0),
    "n_data": ("residuals", None, 1.0),
    "samples": ("samples", None, 1.0),
    "failed": ("failed samples", None, 1.0),
    "seed": ("seed", None, 1.0),
    "level": ("level", "-", 1.0),
    "share_within": ("share within the band", "%", 100.0),
    "coverage": ("coverage", "%", 100.0),
    "coverage_coef": ("coverage, coefficients only", "%", 100.0),
    "start": ("starting slip", "m", 1.0),
    "chi2": ("chi-square", "-", 1.0),
    "chi2_red": ("reduced chi-square", "-", 1.0),
    "dof": ("degrees of freedom", None, 1.0),
    "tau": ("correlation time", "samples", 1.0),
    "n_eff": ("effective samples", "-", 1.0),
    "n": ("samples", None, 1.0),
    "rms": ("RMS residual", "N", 1.0),
    "lag_one": ("lag-one correlation", "-", 1.0),
    "initial_energy": ("initial energy", "J", 1.0),
    "max_energy_error": ("largest energy error", "-", 1.0),
    "mean": ("mean", "-", 1.0),
    "singular_values": ("singular value", "-", 1.0),
    "modes": ("modes", None, 1.0),
    "mode": ("mode", None, 1.0),
    "probability": ("probability", "-", 1.0),
}


def title_of(key: str, own: dict | None = None) -> tuple[str, float]:
    """``(title, scale)`` of the quantity ``key``: from ``own`` (a class's ``COLUMNS``),
    else :data:`QUANTITIES`, else the key itself (text and flags keep their key).
    """
    spec = (own or {}).get(key) or QUANTITIES.get(key)
    if spec is None:
        return str(key), 1.0
    name, unit, *scale = spec
    return column(name, unit), float(scale[0]) if scale else 1.0
