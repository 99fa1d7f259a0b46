"""Shared plumbing of the effect plug-ins: the element protocol around a wrapped joint, the
parameter description every effect declares, and a safeguarded zero finder.

Private module; the public names live in :mod:`iwan_element.effects`.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Callable
from dataclasses import dataclass
from types import MethodType
from typing import Any, cast

import numpy as np
from numpy.typing import NDArray

from ..base.validation import check_scalar, finite_array, same_length
from ..core.parameters import IwanParameters
from ..core.periodic import PeriodicForm
from ..core.protocol import CommittedState, check_element

__all__ = ["ParamSpec", "Effect", "VectorLaw", "declares_vector_form", "_find_zero"]


#: The smallest size an effect's size prior spreads its decades down to, as a fraction of
#: the declared range (:attr:`ParamSpec.neutral`): three decades.
PRIOR_FLOOR = 1e-3


@dataclass(frozen=True)
class ParamSpec:
    """One named parameter of an effect.

    Attributes
    ----------
    name : str
        Keyword of the effect's constructor.
    unit : str
        SI unit.
    meaning : str
        One line of physics.
    lower, upper : float
        Allowed range of the physical value (``upper = inf`` for none).
    default : float or None
        Default value (``None``: the parameter is required).
    fs_power : int
        How the value scales with the joint's force scale ``Fs`` when every force is
        multiplied by ``Fs`` (``+1`` for a stiffness or dashpot, ``-1`` for a rate per joule,
        ``0`` for a length or a ratio). Used by fitting, which eliminates ``Fs`` in closed form.
    ref : str
        Reference scale of the dimensionless fitting variable: ``"u_max"`` (largest |u|),
        ``"v_rms"``, ``"D_ref"`` (energy dissipated by the plain unit-``Fs`` fit over the
        record) or ``"1"`` for loops; ``"zeta_ref"``, ``"omega2_ref"``, ``"X_max"``,
        ``"omega2_per_X2"`` (``omega2_ref / X_max**2``) for modal forms. The fit works on
        ``z = (value / Fs**fs_power) * ref**ref_power``.
    ref_power : int
        Exponent of ``ref`` in the fitting variable.
    fit_bounds : tuple of float
        Bounds of that dimensionless fitting variable.
    fit_starts : tuple of float
        Starting values of that fitting variable (the first is the "no effect" value).
    open_range : bool
        True when the ends of ``[lower, upper]`` are excluded (e.g. an asymmetry of +-1
        would leave one direction without friction).
    prior : tuple of float or None
        The prior of the parameter in the diagnosis' model probabilities
        (:mod:`iwan_element.diagnose.probabilities`): uniform over this range of the
        fitting variable (the same units as ``fit_bounds``, inside them), stated with the
        effect as its physical range in the record's own scales (e.g. a gap of up to half
        the largest stroke). ``None``: the whole of ``fit_bounds``.
    neutral : float or None
        The fitting variable's "no effect" value (0 for a size, 1 for a break-away ratio)
        when the parameter is the effect's size: its prior is then uniform in the
        logarithm of the distance from it, over the decades from :data:`PRIOR_FLOOR` of the
        range to the range's end (density ``1 / (|z - neutral| + floor)``: a size is a
        priori as likely in each of those decades, and flat below the floor). ``None``: a
        uniform prior (a shape, a position).
    """

    name: str
    unit: str
    meaning: str
    lower: float = 0.0
    upper: float = math.inf
    default: float | None = None
    fs_power: int = 0
    ref: str = "1"
    ref_power: int = 1
    fit_bounds: tuple = (0.0, 1.0)
    fit_starts: tuple = (0.0,)
    open_range: bool = False
    prior: tuple | None = None
    neutral: float | None = None

    def __post_init__(self):
        lo, hi = self.fit_bounds
        if self.prior is not None and not (lo <= self.prior[0] < self.prior[1] <= hi):
            raise ValueError(
                f"prior of {self.name!r} must be a range inside fit_bounds "
                f"{self.fit_bounds}, got {self.prior}"
            )

        if self.neutral is not None and not lo <= self.neutral <= hi:
            raise ValueError(f"neutral of {self.name!r} must lie in fit_bounds {self.fit_bounds}")

    @property
    def prior_range(self) -> tuple:
        """``(low, high)`` of the prior in fitting units (``prior`` or ``fit_bounds``)."""
        return tuple(float(x) for x in (self.prior or self.fit_bounds))

    def log_prior(self, z) -> float | NDArray[np.float64]:
        """Log prior density of the fitting variable ``z`` (array or float) over
        :attr:`prior_range` [1 / fitting unit]: uniform, or log-uniform in the distance
        from :attr:`neutral` (see there).
        """
        lo, hi = self.prior_range
        z = np.asarray(z, float)
        if self.neutral is None:
            return np.full(z.shape, -math.log(hi - lo))
        n = min(max(self.neutral, lo), hi)
        f = PRIOR_FLOOR * max(n - lo, hi - n)
        norm = sum(math.log1p(d / f) for d in (n - lo, hi - n) if d > 0)
        return -np.log(np.abs(z - n) + f) - math.log(norm)

    def prior_quantile(self, q) -> float | NDArray[np.float64]:
        """The fitting variable at prior probability ``q`` in [0, 1] (the inverse of the
        prior's distribution function; for nested sampling's prior transform).
        """
        lo, hi = self.prior_range
        q = np.asarray(q, float)
        if self.neutral is None:
            return lo + q * (hi - lo)
        n = min(max(self.neutral, lo), hi)
        f = PRIOR_FLOOR * max(n - lo, hi - n)
        a, b = math.log1p((n - lo) / f), math.log1p((hi - n) / f)  # masses x norm
        m = q * (a + b)
        left = n - f * np.expm1(np.maximum(a - m, 0.0))
        right = n + f * np.expm1(np.maximum(m - a, 0.0))
        return np.clip(np.where(m < a, left, right), lo, hi)


def _find_zero(
    trial, a: float, Fa: float, b: float, Fb: float, *, rtol: float = 1e-13, max_iter: int = 100
) -> float:
    """Zero of a force monotone along the path ``a -> b`` (``Fa``, ``Fb`` of opposite sign),
    by Newton steps on the element's tangent, safeguarded by bisection. ``trial(x)`` returns
    ``(force, tangent)`` for the move from the committed state to ``x``.
    """
    lo, hi = (a, b) if Fa < 0.0 else (b, a)  # F(lo) < 0 < F(hi)
    x = a
    F = Fa
    K = trial(a + 1e-9 * (b - a))[1]
    scale = max(abs(Fa), abs(Fb))
    for _ in range(max_iter):
        x_new = x - F / K if K > 0.0 else 0.5 * (lo + hi)
        if not (min(lo, hi) < x_new < max(lo, hi)):
            x_new = 0.5 * (lo + hi)
        x = x_new
        F, K = trial(x)
        if abs(F) <= rtol * scale or abs(hi - lo) <= 1e-15 * max(abs(a), abs(b), 1e-300):
            break
        if F < 0.0:
            lo = x
        else:
            hi = x
    return x


def monotone_runs(u: np.ndarray):
    """Monotone runs of a displacement history that starts from rest at 0: ``(a, b, d)`` for
    each, samples ``a:b`` moving in direction ``d`` (+1/-1) from ``u[a - 1]`` (0 before the
    first sample). Pauses belong to the run they interrupt; samples before the first move to
    none.
    """
    du = np.diff(u, prepend=0.0)
    nz = np.flatnonzero(du)
    if nz.size == 0:
        return []
    sgn = np.sign(du[nz])
    starts = nz[np.flatnonzero(np.diff(sgn, prepend=0.0))]
    ends = np.append(starts[1:], u.size)
    return [(int(a), int(b), float(np.sign(du[a]))) for a, b in zip(starts, ends)]


def require_plain_joint(inner, subject: str) -> None:
    """Refuse an ``inner`` that is not a plain Iwan joint (``IwanJoint`` or ``DiscreteIwan``
    with ``IwanParameters``): ``subject`` (e.g. ``"break-away"``) changes the joint's own
    sliders, so it must wrap the joint directly.
    """
    if isinstance(inner, Effect) or not isinstance(getattr(inner, "params", None), IwanParameters):
        raise ValueError(
            "inner must be a plain Iwan joint (IwanJoint or DiscreteIwan with "
            f"IwanParameters): {subject} changes the joint's own sliders, so "
            "it wraps the joint directly (put other effects around it)"
        )


class VectorLaw:
    """A history-free effect's added force as a law of the compiled periodic form:
    ``law(u, v) -> (f [N], df/du [N/m], df/dv [N s/m])`` from the class's ``vector_force``
    (around a zero inner force) and ``vector_tangent`` at its parameter ``values``.
    """

    def __init__(self, cls, values: dict):
        self.cls = cls
        self.values = dict(values)

    def __call__(self, u, v):
        """``(f, df/du, df/dv)`` at displacements ``u`` [m] and velocities ``v`` [m/s]."""
        u = np.asarray(u, float)
        f = self.cls.vector_force(np.zeros(u.shape), u, v, **self.values)
        fu, fv = self.cls.vector_tangent(u, v, **self.values)
        return f, np.broadcast_to(fu, u.shape), np.broadcast_to(fv, u.shape)


def declares_vector_form(cls) -> bool:
    """True if the effect class ``cls`` defines a history-free vectorised force."""
    # a classmethod read from its class is a bound method (mypy sees the plain function)
    base = cast(MethodType, Effect.vector_force).__func__
    return getattr(cls.vector_force, "__func__", None) is not base


#: The ways an effect can sit on the joint (``Effect.structure``).
STRUCTURES = ("parallel", "series", "slider", "energy")
#: The data requirements an effect can declare (``Effect.needs``).
NEEDS = ("rate",)


class Effect(CommittedState):
    """Shared plumbing: the wrapped element, energy counters and a generic force history."""

    effect = ""
    #: ParamSpec of each parameter, in the constructor's order.
    specs: tuple = ()
    #: Names of :attr:`specs`, in order (set on each subclass by ``__init_subclass__``).
    parameter_names: tuple[str, ...]
    #: ``trial(u, v=0.0) -> (force [N], tangent [N/m])``: each effect defines it
    #: (:class:`~iwan_element.core.protocol.JointElement`).
    trial: Callable[..., tuple[float, float]]
    #: Keyword options of the constructor that are not physical parameters (discretisation,
    #: extent of a time-domain bank); :func:`make_effect` passes them through.
    options: tuple = ()
    #: How the effect sits on the joint (:data:`STRUCTURES`): ``"parallel"``, a force beside
    #: the joint; ``"series"``, an element between the drive and the joint (a gap), which
    #: defines ``joint_path(u)``; ``"slider"``, a law of the joint's own slider thresholds;
    #: ``"energy"``, a slider law that evolves with the dissipated energy. It sets
    #: ``slider_level`` (must wrap a plain joint) and ``needs_energy``.
    structure: str = "parallel"
    slider_level = False
    needs_energy = False
    #: True for slider-level effects that may wrap one another (their laws multiply).
    composable = False
    #: What a record must hold to test the effect (:data:`NEEDS`): ``"rate"``, the time and
    #: more than one loading rate. A diagnosis reports the effect as untestable otherwise.
    needs: tuple = ()
    #: Values of the first fitting variable a diagnosis scans for starts, or None.
    fit_scan: tuple | None = None
    #: True when the force jumps with a parameter (sliders breaking at once): the fit then
    #: restarts around its result.
    force_jumps: bool = False
    #: Parameters of the amplitude-domain (modal) form, or () if the effect has none.
    modal_specs: tuple = ()
    #: What the modal form changes in a vibration curve: "stiffness" (frequency only, same
    #: dissipation), "dissipation" (adds dissipation per cycle), "" (no modal form). Effects
    #: with a modal form define ``modal_form(X, frequency, damping, zeta0, **modal_values)``
    #: -> (frequency [Hz], damping ratio [-]) on top of a base curve, and
    #: ``modal_to_joint(values, *, modal_mass, slip_per_amplitude, omega0)``.
    kind: str = ""
    #: True when the modal form is a constant damping floor: a vibration test cannot tell it
    #: from a between-test difference of the linear damping (shaker, suspension), so a
    #: vibration diagnosis that fits that difference cannot test it.
    modal_floor: bool = False
    #: Place among the candidates a loop diagnosis tries (:func:`iwan_element.loop_candidates`,
    #: in this order), or ``None`` for an effect a force-displacement record does not test
    #: (one whose form is for the beam model's vibration only).
    loop_rank: int | None = None

    def __init_subclass__(cls, **kw):
        super().__init_subclass__(**kw)
        if cls.structure not in STRUCTURES:
            raise TypeError(
                f"{cls.__name__}.structure must be one of {STRUCTURES}, got {cls.structure!r}"
            )
        unknown = set(cls.needs) - set(NEEDS)
        if unknown:
            raise TypeError(
                f"{cls.__name__}.needs has unknown entries {sorted(unknown)}; known: {NEEDS}"
            )
        derived = {"slider_level", "needs_energy"} & set(vars(cls))
        if derived:
            raise TypeError(
                f"{cls.__name__} sets {sorted(derived)}: these follow from "
                "structure; declare structure instead"
            )
        if cls.structure == "series" and not callable(getattr(cls, "joint_path", None)):
            raise TypeError(
                f"{cls.__name__} is in series with the joint (structure "
                "'series') and must define joint_path(u)"
            )
        cls.parameter_names = tuple(s.name for s in cls.specs)
        cls.slider_level = cls.structure in ("slider", "energy")
        cls.needs_energy = cls.structure == "energy"

    def __init__(self, inner):
        check_element(inner, name="inner")
        self._inner = inner
        self._W = self._D = self._F = self._u = 0.0
        self._has_trial = False

    @property
    def inner(self) -> Any:
        """The wrapped joint element."""
        return self._inner

    @property
    def parameters(self) -> dict:
        """The effect's own parameters (SI units)."""
        return {k: getattr(self, k) for k in self.parameter_names}

    @property
    def params(self) -> IwanParameters:
        """Parameters of the underlying Iwan joint."""
        return self._inner.params

    def describe(self) -> str:
        """One line naming this effect and every effect below it."""
        own = ", ".join(f"{k}={v:.4g}" for k, v in self.parameters.items())
        inner = self._inner
        below = (
            inner.describe()
            if isinstance(inner, Effect)
            else repr(getattr(inner, "params", type(inner).__name__))
        )
        return f"{self.effect}({own}) on {below}"

    def reset(self) -> None:
        """Virgin state, energy counters zero (the wrapped element too)."""
        self._inner.reset()
        self._W = 0.0
        self._D = 0.0
        self._F = 0.0
        self._u = 0.0
        self._reset_own()
        self.revert()

    def _reset_own(self) -> None:
        pass

    def _set_parameters(self, values: dict) -> None:
        """Validate and store the parameters against :attr:`specs`."""
        for sp in self.specs:
            val = values[sp.name]
            if val is None:
                raise ValueError(f"effect {self.effect!r} needs parameter {sp.name!r}")
            setattr(
                self,
                sp.name,
                check_scalar(
                    sp.name,
                    val,
                    low=sp.lower,
                    high=None if math.isinf(sp.upper) else sp.upper,
                    low_open=sp.open_range,
                    high_open=sp.open_range,
                ),
            )

    @classmethod
    def vector_force(cls, F, u, v, **values):
        """Force of this effect around an inner force history ``F`` [N] at displacements ``u``
        [m] and velocities ``v`` [m/s] (arrays), or ``None`` when the effect has no
        history-free vectorised form (the evaluator then runs the element itself).
        """
        return None

    @classmethod
    def vector_tangent(cls, u, v, **values):
        """``(dF/du [N/m], dF/dv [N s/m])`` of the force :meth:`vector_force` adds, at
        displacements ``u`` [m] and velocities ``v`` [m/s] (arrays), or ``None`` when the
        effect declares none. With :meth:`vector_force` it is the effect's compiled periodic
        form (:meth:`periodic_form`).
        """
        return None

    def periodic_form(self) -> PeriodicForm | None:
        """The whole stack's force as the compiled periodic kernel evaluates it
        (:class:`~iwan_element.core.periodic.PeriodicForm`: the harmonic balance's steady
        loops with exact Jacobians), or ``None`` when some layer has no such form (then the
        elements are stepped sample by sample). A parallel effect adds its own form
        (:meth:`_periodic_own`) to the wrapped element's (``periodic_form()`` of the inner
        element, which must define it too).
        """
        below = getattr(self._inner, "periodic_form", None)
        below = below() if callable(below) else None
        own = self._periodic_own() if self.structure == "parallel" else None
        if below is None or own is None:
            return None
        return below.plus(own)

    def _periodic_own(self) -> PeriodicForm | None:
        """The effect's own added force as a :class:`PeriodicForm`: by default its history-
        free :meth:`vector_force` with its :meth:`vector_tangent`, when it declares both.
        """
        cls = type(self)
        vals = self.parameters
        probe = np.zeros(1)
        if not declares_vector_form(cls) or cls.vector_tangent(probe, probe, **vals) is None:
            return None
        return PeriodicForm(laws=(VectorLaw(cls, vals),))

    def revert(self) -> None:
        """Discard the last trial."""
        self._inner.revert()
        self._has_trial = False

    def _set_trial(self, u: float, v: float, F: float) -> None:
        self._tu = float(u)
        self._tv = float(v)
        self._tF = F
        self._has_trial = True

    def commit(self) -> None:
        """Accept the last trial (no-op if there is none)."""
        if not self._has_trial:
            return
        self._commit()
        self._F = self._tF
        self._u = self._tu
        self._has_trial = False

    def _commit(self) -> None:
        raise NotImplementedError

    def force_history(self, u, v=None) -> np.ndarray:
        """Forces [N] for a history ``u`` [m] (and velocities ``v`` [m/s], default zero), shape
        (n,), from the virgin state, on a private copy; this element is untouched.
        """
        uu = finite_array("u", u, ndim=1)
        vv = np.zeros_like(uu) if v is None else finite_array("v", v, ndim=1)
        same_length(u=uu, v=vv)
        el = copy.deepcopy(self)
        el.reset()
        out = np.empty_like(uu)
        for i, (a, b) in enumerate(zip(uu.tolist(), vv.tolist())):
            out[i] = el.trial(a, b)[0]
            el.commit()
        return out

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.describe()}>"
