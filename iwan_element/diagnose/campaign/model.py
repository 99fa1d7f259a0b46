"""The device model of a campaign fit: parameter laws over the test conditions, the records
as the diagnosis prepared them, the joint residual over all records, and its weighted
least-squares fit (:func:`build_model`, :func:`solve`; equations: ``docs/campaign.md``).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import least_squares
from scipy.sparse import lil_matrix

from ...base.progress import tick
from ...base.validation import finite_array
from ...effects import EFFECTS
from ...effects.engine.evaluate import Evaluator
from ...identify.loops.noise import integrated_time
from ..loops import model as M
from ..loops.batch import band_misfit
from ..loops.prepare import dissipation_scale, drive_structure, effect_scales, fitted_samples
from .probability import record_explanations

if TYPE_CHECKING:
    from scipy.sparse import csr_matrix

__all__ = ["CampaignModel", "RecordModel", "build_model", "solve", "full_force"]

#: The joint's quantities every campaign model has a law for (the law's form of each).
BASE_QUANTITIES = ("Fs", "log_phi_max", "chi", "log1p_beta")
BASE_UNITS = {"Fs": "N", "log_phi_max": "ln m", "chi": "1", "log1p_beta": "1"}
BAND = 0.25  # the band misfit's |F| < BAND max|F|


def log_form(spec) -> bool:
    """True for a parameter bounded on one side only (a gap, a drag, a ratio >= 1): its law
    is on ``ln(value - lower)``, which keeps every law value in range without clipping.
    """
    return math.isfinite(spec.lower) and math.isinf(spec.upper)


def effect_quantity(name: str, spec) -> str:
    """Law name of an effect parameter: its value per ``Fs**fs_power`` (the unit-force form,
    homogeneous of degree zero in the force scale), as ``ln(value - lower)`` for a parameter
    bounded on one side (:func:`log_form`).
    """
    suffix = {0: "", 1: "/Fs", -1: "*Fs"}.get(spec.fs_power, f"/Fs^{spec.fs_power}")
    q = f"{name}.{spec.name}{suffix}"
    if log_form(spec):
        return f"ln({q})" if spec.lower == 0 else f"ln({q} - {spec.lower:g})"
    return q


def to_law(spec, value: float) -> float:
    """A unit-force parameter value in its law's form (NaN at the lower bound of a log form:
    no information on the logarithm's scale).
    """
    if not log_form(spec):
        return value
    d = value - spec.lower
    return math.log(d) if d > 0 else math.nan


def from_law(spec, v: float) -> float:
    """Inverse of :func:`to_law`."""
    return spec.lower + math.exp(min(v, 700.0)) if log_form(spec) else v


def quantities(names) -> tuple:
    """``(law names, units, specs)`` of the stack ``names``: the joint's four, then every
    effect parameter in its law form (``specs``: quantity -> (effect, ParamSpec)).
    """
    q, units, specs = list(BASE_QUANTITIES), dict(BASE_UNITS), {}
    for nm in names:
        for sp in EFFECTS[nm].specs:
            k = effect_quantity(nm, sp)
            q.append(k)
            u = {0: sp.unit, 1: f"({sp.unit})/N", -1: f"({sp.unit}) N"}.get(
                sp.fs_power, f"({sp.unit}) N^{-sp.fs_power}"
            )
            units[k] = f"ln({u})" if log_form(sp) else u
            specs[k] = (nm, sp)
    return tuple(q), units, specs


def check_conditions(conditions, n: int):
    """``(names, X)``: condition names (first record's order) and an ``(n, c)`` array."""
    try:
        conds = list(conditions)
    except TypeError:
        raise ValueError("conditions must be a sequence of dicts, one per record") from None
    if len(conds) != n:
        raise ValueError(f"conditions must hold one dict per record ({n}), got {len(conds)}")
    if not all(isinstance(c, dict) for c in conds):
        raise ValueError(
            "conditions must be dicts of named numbers, e.g. {'tension': 30.0, 'frequency': 0.5}"
        )
    names = tuple(str(k) for k in conds[0])
    if not names:
        raise ValueError("conditions must name at least one condition per record")
    X = np.empty((n, len(names)))
    for i, c in enumerate(conds):
        if set(map(str, c)) != set(names):
            raise ValueError(
                f"conditions[{i}] names {sorted(map(str, c))}; every record must "
                f"name the same conditions {sorted(names)}"
            )
        for j, k in enumerate(names):
            try:
                X[i, j] = float(c[k])
            except (TypeError, ValueError):
                raise ValueError(f"conditions[{i}][{k!r}] must be a number, got {c[k]!r}") from None
    finite_array("conditions", X, ndim=2)
    return names, X


def precheck_laws(laws, cnames, X):
    """The checks of :func:`resolve_laws` that need no effect stack (made before the records
    are diagnosed): quantities of known form, conditions that exist and vary, enough
    records for the joint's default laws.
    """
    if laws is not None and not isinstance(laws, dict):
        raise ValueError(f"laws must be a dict {{quantity: conditions}}, got {type(laws).__name__}")
    known = set(BASE_QUANTITIES) | {
        effect_quantity(nm, sp) for nm, cls in EFFECTS.items() for sp in cls.specs
    }
    unknown = sorted(set(laws or {}) - known)
    if unknown:
        raise ValueError(
            f"laws names {unknown}, which are not quantities of any model; they are {sorted(known)}"
        )
    laws = dict(laws or {})
    resolve_laws(laws, tuple(dict.fromkeys(BASE_QUANTITIES + tuple(laws))), cnames, X)


def resolve_laws(laws, qnames, cnames, X):
    """Conditions of each quantity's law: ``laws[q]`` if given (each must vary over the
    records), else every condition that varies. Returns ``(dict q -> tuple, warnings)``.
    """
    varies = {c: bool(np.ptp(X[:, j]) > 0) for j, c in enumerate(cnames)}
    laws = {} if laws is None else dict(laws)
    out, warns = {}, []
    unknown = sorted(set(laws) - set(qnames))
    if unknown:  # an effect the campaign's stack does not have (checked before)
        warns.append(f"laws for {unknown} are not used: the campaign's stack has no such effect")
    for q in qnames:
        if q in laws:
            conds = laws[q]
            conds = (conds,) if isinstance(conds, str) else tuple(conds)
            for c in conds:
                if c not in cnames:
                    raise ValueError(
                        f"laws[{q!r}] names the condition {c!r}; the conditions are {list(cnames)}"
                    )
                if not varies[c]:
                    raise ValueError(
                        f"laws[{q!r}]: the condition {c!r} has one value over "
                        "all records; a law in it cannot be identified"
                    )
            out[q] = tuple(dict.fromkeys(conds))
        else:
            out[q] = tuple(c for c in cnames if varies[c])
    for c in cnames:
        if not varies[c]:
            warns.append(
                f"the condition {c!r} has one value over all records: every law is constant in it"
            )
    n = X.shape[0]
    for q, conds in out.items():
        A = design(X, cnames, conds)
        if A.shape[1] > n:
            raise ValueError(
                f"the law of {q} has {A.shape[1]} coefficients but there are "
                f"only {n} records; give more records or fewer conditions"
            )
        if np.linalg.matrix_rank(A) < A.shape[1]:
            raise ValueError(
                f"the law of {q} in {list(conds)} cannot be identified: these "
                f"conditions are collinear over the {n} records"
            )
    return out, warns


def design(X, cnames, conds, centre=None, scale=None):
    """Design matrix ``[1, (x_c - centre_c) / scale_c ...]`` of a law in ``conds``."""
    cols = [np.ones(X.shape[0])]
    for c in conds:
        j = cnames.index(c)
        m = 0.0 if centre is None else centre[j]
        s = 1.0 if scale is None else scale[j]
        cols.append((X[:, j] - m) / s)
    return np.column_stack(cols)


def record_from_diagnosis(d, max_samples: int) -> dict:
    """What the campaign fit needs of one record's :class:`Diagnosis`: the record as fitted
    (low-passed, displacement from the rest position), the fitted samples, the per-record
    estimates, the noise and the own fit's misfit (plain arrays, picklable).
    """
    t = np.asarray(d.t, float)
    uj = np.asarray(d.u, float) - float(d.offsets["displacement"])
    F = np.asarray(d.F, float)
    keep = fitted_samples(uj.size, max_samples)
    p = d.fit.joint
    own = F - np.asarray(d.force_after, float)
    est, se = (
        {
            "Fs": p.Fs,
            "log_phi_max": math.log(p.phi_max),
            "chi": p.chi,
            "log1p_beta": math.log1p(p.beta),
        },
        {},
    )
    fse = d.fit.stderr or {}
    se["Fs"] = fse.get("Fs", math.nan)
    se["chi"] = fse.get("chi", math.nan)
    se["log1p_beta"] = fse.get("beta", math.nan) / (1.0 + p.beta)
    for e in d.fit.details.get("effects", []):
        for sp in EFFECTS[e["name"]].specs:
            k = effect_quantity(e["name"], sp)
            val = float(e["parameters"][sp.name]) / p.Fs**sp.fs_power
            s_val = float(e["stderr"].get(sp.name) or math.nan) / p.Fs**sp.fs_power
            est[k] = to_law(sp, val)
            se[k] = s_val / (val - sp.lower) if log_form(sp) else s_val
    base = d.base_fit.joint
    return {
        "t": t,
        "u": uj,
        "F": F,
        "keep": keep,
        "effects": tuple(d.effects),
        "estimates": est,
        "stderr": se,
        "start": float(d.details["start_displacement"]),
        "sigma": float(d.noise_sigma),
        "rms_own": float(np.sqrt(np.mean(own[keep] ** 2))),
        "tau_own": max(1.0, integrated_time(own[keep])),
        "band_own": band_misfit(F, F - own, BAND),
        "base_shape": (base.phi_max, base.chi, base.beta),
        "success": bool(d.success),
        **record_explanations(d),
    }


class RecordModel:
    """One record in a campaign: its evaluator on the fitted samples, its scales and weight."""

    def __init__(self, rec: dict, *, full: bool = False):
        u, t = rec["u"], rec["t"]
        v = np.gradient(u, t)
        keep = np.arange(u.size) if full else rec["keep"]
        rev, tol = drive_structure(u)
        self.ev = Evaluator(u, v, keep, rev, tol=tol)
        self.y = rec["F"][keep]
        self.x_max = self.ev.x_max
        self.scales = effect_scales(u, v, dissipation_scale(self.ev, rec["base_shape"]))
        self.weight = 1.0 / (max(rec["sigma"], rec["rms_own"]) * math.sqrt(rec["tau_own"]))


class CampaignModel:
    """Law coefficients ``c`` (internal: divided by a scale per quantity, conditions centred
    and scaled) and the starting states of the records whose diagnosis fitted one.

    ``theta = [c of every quantity..., start_r / x_max_r for each free start]``.
    """

    def __init__(self, records, names, laws, cnames, X, centre, cscale, qscale, free_start):
        self.records, self.names, self.laws = records, tuple(names), laws
        self.cnames, self.X, self.centre, self.cscale = cnames, X, centre, cscale
        self.qnames = tuple(laws)
        self.qscale = qscale
        self.slices, k = {}, 0
        for q in self.qnames:
            n = 1 + len(laws[q])
            self.slices[q] = slice(k, k + n)
            k += n
        self.n_glob = k
        self.start_pos = {}
        for r, free in enumerate(free_start):
            if free:
                self.start_pos[r] = k
                k += 1
        self.n_theta = k
        self.rows = np.cumsum([0] + [rm.y.size for rm in records])

    def law_values(self, theta, x) -> dict:
        """Each quantity's law value at the conditions ``x`` (a vector in ``cnames`` order)."""
        out = {}
        for q in self.qnames:
            a = design(np.atleast_2d(x), self.cnames, self.laws[q], self.centre, self.cscale)[0]
            out[q] = float(a @ theta[self.slices[q]]) * self.qscale[q]
        return out

    def physical(
        self, vals, rm
    ) -> tuple[float, tuple[float, float, float], list[dict[str, float]]]:
        """``(Fs, shape, effect dicts)`` of law values on record model ``rm`` (clipped into
        the range a fit may take there).
        """
        x = rm.x_max
        phi = x * min(
            max(math.exp(min(vals["log_phi_max"], 700.0)) / x, M.PHI_RANGE[0]), M.PHI_RANGE[1]
        )
        chi = min(max(vals["chi"], M.CHI_BOUNDS[0]), M.CHI_BOUNDS[1])
        beta = math.expm1(min(max(vals["log1p_beta"], 0.0), math.log1p(M.BETA_MAX)))
        effs = []
        for nm in self.names:
            d = {}
            for sp in EFFECTS[nm].specs:
                ref = rm.scales[sp.ref] ** sp.ref_power
                z = min(
                    max(from_law(sp, vals[effect_quantity(nm, sp)]) * ref, sp.fit_bounds[0]),
                    sp.fit_bounds[1],
                )
                d[sp.name] = z / ref
            effs.append(d)
        return vals["Fs"], (phi, chi, beta), effs

    def clipped(self, theta) -> dict:
        """Quantities whose law leaves the range a record's fit may take, with the records
        where it does: ``{quantity: [record index, ...]}``. There :meth:`physical` clips the
        value, the misfit no longer depends on the law's coefficients, and their standard
        errors claim a precision the records do not give.
        """
        out: dict[str, list[int]] = {}
        for r, rm in enumerate(self.records):
            vals = self.law_values(theta, self.X[r])
            _, (phi, chi, beta), effs = self.physical(vals, rm)  # the one place that clips
            pairs = {
                "log_phi_max": (phi, math.exp(min(vals["log_phi_max"], 700.0))),
                "chi": (chi, vals["chi"]),
                "log1p_beta": (beta, math.expm1(min(vals["log1p_beta"], 700.0))),
            }
            for nm, d in zip(self.names, effs):
                for sp in EFFECTS[nm].specs:
                    q = effect_quantity(nm, sp)
                    pairs[q] = (d[sp.name], from_law(sp, vals[q]))
            for q, (used, law) in pairs.items():
                if not math.isclose(used, law, rel_tol=1e-9):
                    out.setdefault(q, []).append(r)
        return out

    def start(self, theta, r) -> float:
        """Slip ``u0`` [m] at the start of record ``r`` (fitted start times ``x_max``; 0: none)."""
        k = self.start_pos.get(r)
        return 0.0 if k is None else float(theta[k]) * self.records[r].x_max

    def record_force(self, theta, r, vals=None, start=None) -> NDArray[np.float64] | None:
        """``Fs g`` [N] of record ``r`` at its fitted samples (no offset), or None if the
        model cannot be evaluated there.
        """
        rm = self.records[r]
        vals = self.law_values(theta, self.X[r]) if vals is None else vals
        Fs, shape, effs = self.physical(vals, rm)
        if not Fs > 0:
            return None
        rm.ev.set_start(self.start(theta, r) if start is None else start)
        try:
            g = rm.ev.unit_force(shape, self.names, effs)
        except (ValueError, ZeroDivisionError, OverflowError, FloatingPointError):
            return None
        return Fs * g if np.all(np.isfinite(g)) else None

    def record_residual(self, theta, r) -> NDArray[np.float64]:
        """Unweighted residual of record ``r``, the offset eliminated (its mean)."""
        rm = self.records[r]
        m = self.record_force(theta, r)
        if m is None:
            return np.full(rm.y.size, 1e3 * float(np.std(rm.y)) + 1.0)
        e = rm.y - m
        return e - e.mean()

    def residual(self, theta) -> NDArray[np.float64]:
        """Weighted residual of all records, stacked (the least-squares objective)."""
        return np.concatenate(
            [rm.weight * self.record_residual(theta, r) for r, rm in enumerate(self.records)]
        )

    def sparsity(self) -> csr_matrix:
        """Jacobian structure: every row depends on the law coefficients, a start only on
        its own record's rows.
        """
        S = lil_matrix((int(self.rows[-1]), self.n_theta), dtype=np.int8)
        S[:, : self.n_glob] = 1
        for r, k in self.start_pos.items():
            S[self.rows[r] : self.rows[r + 1], k] = 1
        return S.tocsr()

    def jacobian(self, theta) -> NDArray[np.float64]:
        """Unweighted Jacobian ``d residual / d theta`` by central differences (two steps;
        samples whose force jumps between them are left out, :func:`..loops.model.jumps`).
        """
        J = np.zeros((int(self.rows[-1]), self.n_theta))

        def diff(j, h, rs):
            out = []
            for f in (1.0, 4.0):
                tp, tm = theta.copy(), theta.copy()
                tp[j] += f * h
                tm[j] -= f * h
                out.append(
                    [
                        (self.record_residual(tp, r) - self.record_residual(tm, r)) / (2 * f * h)
                        for r in rs
                    ]
                )
            for r, d1, d4 in zip(rs, *out):
                J[self.rows[r] : self.rows[r + 1], j] = np.where(M.jumps(d1, d4), 0.0, d1)

        every = range(len(self.records))
        for j in range(self.n_glob):
            diff(j, 1e-5, every)
        for r, k in self.start_pos.items():
            diff(k, 1e-4, [r])
        return J


def build_model(preps, names, laws, cnames, X) -> CampaignModel:
    """The :class:`CampaignModel` of prepared records (scales and centring from them)."""
    records = [RecordModel(p) for p in preps]
    centre = X.mean(axis=0)
    cscale = np.where(X.std(axis=0) > 0, X.std(axis=0), 1.0)
    qscale = {
        "Fs": float(np.median([p["estimates"]["Fs"] for p in preps])),
        "log_phi_max": 1.0,
        "chi": 1.0,
        "log1p_beta": 1.0,
    }
    for nm in names:
        for sp in EFFECTS[nm].specs:
            qscale[effect_quantity(nm, sp)] = (
                1.0
                if log_form(sp)
                else float(np.median([rm.scales[sp.ref] ** -sp.ref_power for rm in records]))
            )
    free = [p["start"] != 0.0 for p in preps]
    return CampaignModel(records, names, laws, cnames, X, centre, cscale, qscale, free)


def solve(model, theta0, *, max_nfev, bar=None) -> Any:
    """The joint weighted least-squares fit (trust region, sparse finite differences)."""

    def fun(th):
        tick(bar)
        return model.residual(th)

    return least_squares(
        fun,
        theta0,
        jac_sparsity=model.sparsity(),
        method="trf",
        x_scale="jac",
        diff_step=1e-6,
        max_nfev=max_nfev,
    )


def full_force(
    model, theta, r, prep, vals=None, start=None
) -> tuple[NDArray[np.float64] | None, float]:
    """Campaign force [N] of record ``r`` at every sample, offset included (fitted on the
    record's fitted samples), and the offset.
    """
    rm_full = RecordModel(prep, full=True)
    vals = model.law_values(theta, model.X[r]) if vals is None else vals
    start = model.start(theta, r) if start is None else start
    m_keep = model.record_force(theta, r, vals=vals, start=start)
    if m_keep is None:
        return None, math.nan
    F0 = float(np.mean(model.records[r].y - m_keep))
    Fs, shape, effs = model.physical(vals, rm_full)
    rm_full.ev.set_start(start)
    return Fs * rm_full.ev.unit_force(shape, model.names, effs) + F0, F0
