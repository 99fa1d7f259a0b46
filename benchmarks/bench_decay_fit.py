"""Direct decay fit (issue 22, item 2): coverage of the stated standard errors.

Seeded free decays of one modal Iwan mode with damping from 0.05 % to 3 % at the release
amplitude, 1 % white noise (of the record's peak), a second linear mode at 0.8-0.9 or
1.1-1.4 f0, measured as displacement, velocity or acceleration (in turn). Two routes that
share no code with the fit (``tests/_decays.py``): the exact Iwan oscillator integrated in
time (``joint_decay``; even cases) and the slowly-varying-amplitude equations integrated by
``solve_ivp`` with the closed-form curves (``svam_decay``; odd cases). The truth is the modal
Iwan closed form (first-harmonic stiffness, dashpot floor). Each case is fitted with
:func:`iwan_element.fit_decay`; a parameter counts when the result marks it identified
(``fit.identified``), and it is covered when ``|value - truth| <= 2 stderr``; the coverage is
printed over all fits and over those with ``success=True``, with each fit's ``noise_dof``.

    PYTHONPATH=. python benchmarks/bench_decay_fit.py --cases 50 [--workers 2]
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
from scipy.optimize import brentq

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from _decays import QUANTITIES, joint_decay, svam_decay

from iwan_element import IwanParameters, fit_decay, modal_iwan_curve

PHI_MAX = 1e-3


def draw_case(seed):
    """True parameters, release amplitude and record of one case."""
    rng = np.random.default_rng(seed)
    f0 = rng.uniform(40.0, 150.0)
    w02 = (2 * math.pi * f0) ** 2
    chi, beta, kappa = rng.uniform(-0.7, -0.2), rng.uniform(0.1, 1.0), rng.uniform(0.02, 0.1)
    KT = kappa * w02
    c = beta + (chi + 1) / (chi + 2)
    p = IwanParameters(KT * c * PHI_MAX / (1 + beta), KT, chi, beta)
    k_inf = w02 - KT
    zeta_target = math.exp(rng.uniform(math.log(5e-4), math.log(3e-2)))
    zeta0 = zeta_target * rng.uniform(0.3, 0.9)

    def joint_part(q):
        return modal_iwan_curve(q, p, K_inf=k_inf, stiffness="harmonic")[1] - (zeta_target - zeta0)

    hi = 3 * PHI_MAX
    q0 = brentq(joint_part, 1e-7 * PHI_MAX, hi) if joint_part(hi) > 0 else hi
    ratio = rng.choice([rng.uniform(0.8, 0.9), rng.uniform(1.1, 1.4)])
    fs = f0 * rng.uniform(20.0, 40.0)
    duration = min(5.0 / (zeta0 * 2 * math.pi * f0), 8.0, 40000 / fs)
    return dict(
        p=p,
        k_inf=k_inf,
        zeta0=zeta0,
        q0=q0,
        ratio=ratio,
        fs=fs,
        duration=duration,
        f0=f0,
        quantity=QUANTITIES[seed % 3],
        route="joint" if seed % 2 == 0 else "svam",
        rng=rng,
    )


def make_record(c):
    p, k_inf, zeta0 = c["p"], c["k_inf"], c["zeta0"]
    kw = dict(
        duration=c["duration"],
        fs=c["fs"],
        quantity=c["quantity"],
        ratio=c["ratio"],
        second=0.3,
        noise=0.01,
        rng=c["rng"],
    )
    if c["route"] == "joint":
        return joint_decay(p, K_inf=k_inf, zeta0=zeta0, q0=c["q0"], **kw)

    def curves(a):
        a = np.asarray(a, dtype=float)
        f, z = modal_iwan_curve(
            np.atleast_1d(a),
            p,
            K_inf=k_inf,
            zeta0=zeta0,
            stiffness="harmonic",
            floor="dashpot",
            damping_form="decay",
        )
        return np.asarray(f).reshape(a.shape), np.asarray(z).reshape(a.shape)

    return svam_decay(lambda a: curves(a)[0], lambda a: curves(a)[1], a0=c["q0"], **kw)


def truth(c, fit):
    p, k_inf = c["p"], c["k_inf"]
    x_ref = fit.conventions["x_ref"]
    w02 = k_inf + p.KT
    out = {
        "f0": math.sqrt(w02) / (2 * math.pi),
        "zeta0": c["zeta0"],
        "chi": p.chi,
        "delta": p.KT * (x_ref / p.phi_max) ** (p.chi + 1) / (w02 * (p.chi + 2) * (1 + p.beta)),
    }
    out.update(beta=p.beta, kappa=p.KT / w02, phi_max=p.phi_max, KT=p.KT, K_inf=k_inf, Fs=p.Fs)
    return out


def run_case(seed):
    c = draw_case(seed)
    rec = make_record(c)
    t0 = time.perf_counter()
    try:
        fit = fit_decay(rec.t, rec.y, quantity=rec.quantity, band=rec.band)
    except ValueError as exc:
        return dict(seed=seed, error=str(exc), c=_describe(c))
    tr = truth(c, fit)
    z = {
        k: (fit.parameters[k] - tr[k]) / fit.stderr[k] if fit.stderr[k] > 0 else math.inf
        for k in fit.identified
    }
    zeta_q0 = float(
        modal_iwan_curve(
            c["q0"],
            c["p"],
            K_inf=c["k_inf"],
            zeta0=c["zeta0"],
            stiffness="harmonic",
            floor="dashpot",
        )[1]
    )
    return dict(
        seed=seed,
        c=_describe(c),
        zeta_q0=zeta_q0,
        regime=fit.regime,
        success=fit.success,
        z=z,
        reported=list(fit.parameters),
        nu=fit.conventions["noise_dof"],
        beyond=c["q0"] > c["p"].phi_max,
        seconds=time.perf_counter() - t0,
    )


def _describe(c):
    return (
        f"{c['route']:5s} {c['quantity'][:5]:5s} f0={c['f0']:6.1f} ratio={c['ratio']:.2f} "
        f"q0/phimax={c['q0'] / PHI_MAX:.3g} T={c['duration']:.3g}s fs={c['fs']:.0f}"
    )


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=50)
    ap.add_argument("--seed0", type=int, default=0)
    ap.add_argument("--workers", type=int, default=1)
    args = ap.parse_args(argv)
    seeds = range(args.seed0, args.seed0 + args.cases)
    t0 = time.perf_counter()
    if args.workers > 1:
        with ProcessPoolExecutor(args.workers) as ex:
            rows = list(ex.map(run_case, seeds))
    else:
        rows = [run_case(s) for s in seeds]
    for r in rows:
        if "error" in r:
            print(f"seed {r['seed']:3d} {r['c']}  ERROR {r['error']}")
    n_err = sum("error" in r for r in rows)
    print(f"{len(rows)} cases, {n_err} raised, {time.perf_counter() - t0:.0f} s")
    ok = [r for r in rows if "error" not in r]
    for r in ok:
        zs = " ".join(f"{k}={v:+.2f}" for k, v in r["z"].items())
        print(
            f"seed {r['seed']:3d} {r['c']} zeta(q0)={100 * r['zeta_q0']:.3f}% "
            f"{r['regime']:9s} success={str(r['success']):5s} nu={r['nu']:5.1f} "
            f"{r['seconds']:5.1f}s  {zs}"
        )
    _coverage(ok, "all fits")
    _coverage([r for r in ok if r["success"]], "fits with success=True")
    _regime_counts(ok)


def _coverage(rows, label):
    """Coverage of 2 stderr per parameter and overall over ``rows``."""
    hits, counts, worst = {}, {}, []
    for r in rows:
        for k, v in r["z"].items():
            counts[k] = counts.get(k, 0) + 1
            hits[k] = hits.get(k, 0) + (abs(v) <= 2.0)
        worst += [abs(v) for v in r["z"].values()]
    print(f"coverage of identified parameters within 2 stderr, {label} ({len(rows)}):")
    for k in counts:
        print(f"  {k:8s} {hits[k]:3d}/{counts[k]:3d} = {100 * hits[k] / counts[k]:5.1f} %")
    tot_h, tot_n = sum(hits.values()), sum(counts.values())
    if tot_n:
        print(
            f"  overall  {tot_h:3d}/{tot_n:3d} = {100 * tot_h / tot_n:5.1f} %  "
            f"(largest |z| {max(worst):.3g})"
        )


def _regime_counts(rows):
    """Reported regime and success against where the release was (the truth's phi_max)."""
    print("regimes (release above / below phi_max):")
    for beyond in (True, False):
        sub = [r for r in rows if r["beyond"] == beyond]
        tally = {}
        for r in sub:
            key = f"{r['regime']}, success={r['success']}"
            tally[key] = tally.get(key, 0) + 1
        print(
            f"  {'above' if beyond else 'below'} ({len(sub)}): "
            + "; ".join(f"{k}: {v}" for k, v in sorted(tally.items()))
        )


if __name__ == "__main__":
    main()
