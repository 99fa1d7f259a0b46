"""The four parameters of Segalman's Iwan joint model and the quantities derived from them.

References
----------
Segalman, D. J. (2005), "A four-parameter Iwan model for lap-type joints",
J. Appl. Mech. 72, 752-760 (cited as "Segalman 2005").
Li, Cai, Ruan, Cai, "Hysteresis modelling and identification of bolted joints with the Iwan
model" (the seed paper, cited as "paper eq. N"). Its eq. (8) prints ``phi_max**(chi+2)`` in
``S``; the correct power is 1 (see ``S`` below).
"""

from __future__ import annotations

import json
import math
import sys
from dataclasses import asdict, dataclass, field
from os import PathLike
from pathlib import Path

import numpy as np

from ..base.result_shape import html_table
from ..base.validation import check_scalar

__all__ = ["IwanParameters"]

#: Largest accepted ``chi``. Physical joints have ``-1 < chi <= 0``; at ``chi = 1e6`` the
#: continuous density already sits within 1e-4 phi_max of phi_max (a spike), and beyond
#: ~1e150 the products ``(chi+2)(chi+3)`` of the closed forms overflow.
CHI_MAX = 1e6

_LOG_HUGE = math.log(sys.float_info.max)
_LOG_TINY = math.log(sys.float_info.min)


def _derived(Fs: float, KT: float, chi: float, beta: float) -> tuple[float, float]:
    """``phi_max`` [m] and ``S`` [N/m] (paper eqs. 8, 11), checked for float range.

    Every derived quantity the package uses is a product of ``phi_max``, ``KT``, ``Fs`` and
    powers ``r**(chi+k)`` of ``r = u/phi_max <= 1`` (never of ``phi_max`` itself), so finite,
    normal ``phi_max``, ``1/phi_max``, ``KT phi_max`` and ``KT phi_max**2`` are enough for all
    closed forms and the time-domain elements to stay finite.
    """
    c = beta + (chi + 1.0) / (chi + 2.0)  # in (0, inf); ratio below <= 1/c
    ratio = (1.0 + beta) / c
    with np.errstate(all="ignore"):
        phi_max = float(np.float64(Fs) / np.float64(KT) * np.float64(ratio))  # paper eq. 11
        checks = {
            "phi_max = Fs (1+beta)/(KT c)": phi_max,
            "1/phi_max": 1.0 / phi_max if phi_max else math.inf,
            "KT phi_max": KT * phi_max,
            "KT phi_max**2": KT * phi_max * phi_max,
        }
    for what, v in checks.items():
        if not (math.isfinite(v) and v >= sys.float_info.min):
            raise ValueError(
                f"IwanParameters(Fs={Fs}, KT={KT}, chi={chi}, beta={beta}) are outside the "
                f"float range: {what} = {v}; rescale the units (e.g. mm and kN) so that Fs, "
                f"KT and Fs/KT are between about 1e-150 and 1e150"
            )
    S = KT * (beta / (1.0 + beta))  # = (Fs/phi_max) beta / c
    return phi_max, S


@dataclass(frozen=True)
class IwanParameters:
    """Segalman's four-parameter Iwan model (paper eqs. 3-11, Segalman 2005 eqs. 9-17).

    The slider density over slip displacement ``phi`` [m] is (paper eq. 3)::

        rho(phi) = R phi**chi [H(phi) - H(phi - phi_max)] + S delta(phi - phi_max)

    Parameters
    ----------
    Fs : float
        Macroslip (joint slip) force [N], ``Fs > 0``.
    KT : float
        Tangential stiffness of the unslipped joint [N/m], ``KT > 0``.
    chi : float
        Exponent of the power-law slider density [-], ``-1 < chi <= 1e6``. Physical joints
        have ``-1 < chi <= 0`` (dissipation grows with force amplitude to the power 2..3).
        Large ``chi`` is computed without overflow (all powers are of ``u/phi_max``).
    beta : float
        Ratio of the spike strength to the continuous part (paper eq. 6) [-], ``beta >= 0``.

    Raises
    ------
    ValueError
        If a value is not finite or outside its range (the message names the argument), or
        if ``phi_max``, ``1/phi_max``, ``KT phi_max`` or ``KT phi_max**2`` fall outside the
        normal float range (units far from SI scale; the message says which).

    Examples
    --------
    >>> p = IwanParameters(Fs=3.0, KT=2.0, chi=-0.1, beta=0.1)
    >>> round(p.phi_max, 5)
    2.87615
    """

    Fs: float
    KT: float
    chi: float
    beta: float
    _derived: tuple = field(init=False, repr=False, compare=False, hash=False)

    def __post_init__(self) -> None:
        Fs = check_scalar("Fs", self.Fs, low=0.0, low_open=True)
        KT = check_scalar("KT", self.KT, low=0.0, low_open=True)
        chi = check_scalar("chi", self.chi, low=-1.0, low_open=True, high=CHI_MAX)
        beta = check_scalar("beta", self.beta, low=0.0)
        for name, val in (("Fs", Fs), ("KT", KT), ("chi", chi), ("beta", beta)):
            object.__setattr__(self, name, val)
        phi_max, S = _derived(Fs, KT, chi, beta)
        object.__setattr__(self, "_derived", (phi_max, S))

    # ------------------------------------------------------------------ derived
    @property
    def phi_max(self) -> float:
        """Slip displacement of the strongest slider [m] (paper eq. 11)."""
        return self._derived[0]

    @property
    def K_slider(self) -> float:
        """Stiffness of the continuous part of the density, ``KT - S = KT/(1+beta)`` [N/m]
        (so that ``R phi_max**(chi+1) = (chi+1) K_slider``, free of overflow).
        """
        return self.KT / (1.0 + self.beta)

    @property
    def R(self) -> float:
        """Coefficient of the power-law density [N m**(-chi-2)] (paper eq. 7).

        ``R = (chi+1) KT / ((1+beta) phi_max**(chi+1))`` (docs/equations.md section 2,
        ``KT = R phi_max**(chi+1)/(chi+1) + S``). Its unit depends on ``chi``, so for large
        ``chi`` or ``phi_max`` far from 1 m it may not be representable as a float; the
        closed forms never use it (they use ``r = u/phi_max``). Raises ``ValueError`` then.
        """
        pm, chi = self._derived[0], self.chi
        log_r = (
            math.log(chi + 1.0)
            + math.log(self.KT)
            - math.log1p(self.beta)
            - (chi + 1.0) * math.log(pm)
        )
        if not _LOG_TINY < log_r < _LOG_HUGE:
            raise ValueError(
                f"R = 10**{log_r / math.log(10.0):.1f} N m**(-chi-2) is outside the float range "
                f"for chi={chi}, phi_max={pm:g} m; the model itself is well defined (use "
                f"K_slider and phi_max: R phi_max**(chi+1) = (chi+1) K_slider)"
            )
        try:
            return (chi + 1.0) * self.K_slider / pm ** (chi + 1.0)
        except (OverflowError, ZeroDivisionError):  # R fits but phi_max**(chi+1) does not
            return math.exp(log_r)

    @property
    def S(self) -> float:
        """Strength of the Dirac spike at ``phi_max`` [N/m] (paper eq. 8, corrected:
        ``S = (Fs/phi_max) beta / (beta + (chi+1)/(chi+2)) = KT beta/(1+beta)``).
        """
        return self._derived[1]

    @property
    def macroslip_displacement(self) -> float:
        """Displacement at which the virgin curve reaches ``Fs`` [m] (equals ``phi_max``)."""
        return self._derived[0]

    # ------------------------------------------------------------------ I/O
    def to_dict(self) -> dict:
        """JSON-safe dict of the four parameters, with units."""
        return {
            "Fs": self.Fs,
            "KT": self.KT,
            "chi": self.chi,
            "beta": self.beta,
            "units": {"Fs": "N", "KT": "N/m", "chi": "1", "beta": "1"},
        }

    def _repr_html_(self) -> str:
        """The four parameters and the derived ones as an HTML table (a notebook's view),
        SI units.
        """
        rows = [
            ("Fs", self.Fs, "N", "macroslip force"),
            ("KT", self.KT, "N/m", "stuck tangential stiffness"),
            ("chi", self.chi, "-", "slider density exponent"),
            ("beta", self.beta, "-", "spike strength over the continuous part"),
            ("phi_max", self.phi_max, "m", "slip of the strongest slider (derived)"),
            ("R", self.R, "N m^(-chi-2)", "density coefficient (derived)"),
            ("S", self.S, "N/m", "spike strength (derived)"),
        ]
        return "<p><b>IwanParameters</b></p>" + html_table(
            "Iwan parameters", ("parameter", "value", "unit", "meaning"), rows
        )

    @classmethod
    def from_dict(cls, data: dict) -> IwanParameters:
        """Build from a dict as written by :meth:`to_dict` (extra keys other than ``units``
        are rejected so that a misspelt key is not silently ignored).
        """
        if not isinstance(data, dict):
            raise ValueError(f"data must be a dict, got {type(data).__name__}")
        allowed = {"Fs", "KT", "chi", "beta", "units"}
        unknown = set(data) - allowed
        if unknown:
            raise ValueError(
                f"unknown keys in parameter dict: {sorted(unknown)}; allowed are {sorted(allowed)}"
            )
        missing = {"Fs", "KT", "chi", "beta"} - set(data)
        if missing:
            raise ValueError(f"parameter dict lacks {sorted(missing)}")
        units = data.get("units")
        if units is not None and not isinstance(units, dict):
            raise ValueError(
                f"units must be a dict such as {{'Fs': 'N', 'KT': 'N/m'}}, got {units!r}"
            )
        if units is not None:
            expected = {"Fs": "N", "KT": "N/m", "chi": "1", "beta": "1"}
            for k, v in units.items():
                if k in expected and v != expected[k]:
                    raise ValueError(f"units[{k!r}] must be {expected[k]!r} (SI), got {v!r}")
        return cls(data["Fs"], data["KT"], data["chi"], data["beta"])

    def save(self, path: str | PathLike) -> Path:
        """Write the parameters as JSON to ``path``; return the path."""
        p = Path(path)
        p.write_text(json.dumps(self.to_dict(), indent=2) + "\n")
        return p

    @classmethod
    def load(cls, path: str | PathLike) -> IwanParameters:
        """Read parameters written by :meth:`save`."""
        return cls.from_dict(json.loads(Path(path).read_text()))

    def replace(self, **changes: float) -> IwanParameters:
        """Return a copy with some of ``Fs, KT, chi, beta`` changed (validated again)."""
        fields = {"Fs", "KT", "chi", "beta"}
        bad = set(changes) - fields
        if bad:
            raise ValueError(f"unknown parameter names {sorted(bad)}; allowed are {sorted(fields)}")
        d = {k: v for k, v in asdict(self).items() if k in fields}
        d.update(changes)
        return IwanParameters(**d)
