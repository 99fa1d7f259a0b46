"""Campaign fit benchmark: coverage of the stated uncertainty, and the real damper campaign.

``--coverage N``: N seeded synthetic campaigns (tests/_campaign_cases.py: 8 records of a joint
with backlash, Fs linear in a "tension", chi linear in a "frequency", the rest constant,
0.5 % white force noise, each quantity fitted with a law linear in both conditions: 18
coefficients); the share of coefficients whose true value lies within 2 stated standard
errors (target 90-98 %, i.e. about 95 %), overall and per quantity.

``--real``: the campaign fit over every given record of the ARTS banded rotary friction
damper (dataset-1: 12 records, dataset-2: 17 records; CC BY-SA 4.0, read from
../shared/data), each diagnosed with the README's recipe (``lowpass=20``), conditions from
the file names: band tension [lb], drive frequency [Hz] and the campaign (0: dataset-1 of
2022, 1: dataset-2 of April 2023, a year apart), optionally the nominal stroke [in]
(``--stroke``; dataset-1's is about 1 in). Prints the laws with their standard errors, the
per-record table, the leave-one-out table (band misfit |F| < 0.25 max|F| of the prediction
from the other records over the record's own fit's; target <= 1.5 on >= 80 % of records)
and the times. Per-record diagnoses are cached in ``--cache`` (pickles) so that a second
run fits the campaign only.

    python benchmarks/bench_campaign.py --coverage 40 [--fs-scatter 0.1]
    python benchmarks/bench_campaign.py --real [--jobs 2] [--cache DIR] [--loo full]
        [--effects backlash,asymmetric_slip] [--stroke] [--interaction] [--quadratic]
        [--laws campaign] [--band] [--attribute] [--neighbours]
"""

import argparse
import pickle
import re
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))


def coverage(n, fs_scatter=0.0):
    """Share of true law coefficients within 2 stated standard errors (``stderr``, and
    ``stderr_scatter``: with the record-to-record scatter) over ``n`` seeded campaigns whose
    records' Fs scatter by ``fs_scatter`` (ln Fs standard deviation) about the law.
    """
    from _campaign_cases import LAWS, campaign

    from iwan_element import fit_campaign

    hits, per_q, t0, bad = [], {q: [] for q in LAWS}, time.perf_counter(), 0
    hits_s, per_q_s = [], {q: [] for q in LAWS}
    for seed in range(n):
        recs, conds = campaign(1000 + seed, fs_scatter=fs_scatter)
        fit = fit_campaign(recs, conds, effects=("backlash",), candidates=("backlash",))
        bad += not fit.success
        for q, true in LAWS.items():
            for term, v in zip(("1", "tension", "frequency"), true):
                err = abs(fit.coefficients[q][term] - v)
                ok = err <= 2.0 * fit.stderr[q][term]
                hits.append(ok)
                per_q[q].append(ok)
                ok = err <= 2.0 * fit.stderr_scatter[q][term]
                hits_s.append(ok)
                per_q_s[q].append(ok)
    print(
        f"{n} campaigns x {len(hits) // n} coefficients in {time.perf_counter() - t0:.0f} s; "
        f"{bad} fits not successful; Fs scatter {fs_scatter:g} (ln Fs)"
    )
    for q in per_q:
        print(
            f"  {q:<20} {100 * np.mean(per_q[q]):5.1f} % within 2 stderr, "
            f"{100 * np.mean(per_q_s[q]):5.1f} % within 2 stderr_scatter"
        )
    print(
        f"coverage of the law coefficients by 2 stderr: {100 * np.mean(hits):.1f} % "
        f"(target 90-98 %); by 2 stderr_scatter: {100 * np.mean(hits_s):.1f} %"
    )


def _conditions(path, stroke, interaction=False, quadratic=False):
    m = re.match(r"ds(\d)_(\d+(?:p\d+)?)Hz_(\d+)lb(?:_(\d+(?:p\d+)?)in)?", path.stem)
    ds, f, T, a = m.groups()
    c = {
        "tension": float(T),
        "frequency": float(f.replace("p", ".")),
        "campaign": float(int(ds) - 1),
    }
    if stroke:
        c["stroke"] = float(a.replace("p", ".")) if a else 1.0
    if interaction:  # a slope in tension of its own for each campaign
        c["campaign_x_tension"] = c["campaign"] * c["tension"]
    if quadratic:  # a curvature in tension (saturation at 70-80 lb)
        c["tension_squared"] = c["tension"] ** 2
    return c


#: Law sets of ``--laws`` (the conditions each quantity's law is linear in; derived
#: conditions made by :func:`_conditions`), chosen with the device's physics:
#: docs/campaign.md section 8.
LAW_SETS = {
    "linear": None,  # every quantity linear in every condition (the default)
    "campaign": {
        # a slip-force law in tension of its own per campaign, with curvature (dataset-1
        # saturates, dataset-2 rises steeply from 30 to 36 lb), plus rate and stroke
        "Fs": (
            "campaign",
            "tension",
            "campaign_x_tension",
            "tension_squared",
            "campaign_x_tension_squared",
            "frequency",
            "stroke",
        ),
        # the asymmetry changes sign with tension in dataset-2 and grows with rate and
        # stroke at 0 lb (ds2 README)
        "asymmetric_slip.asymmetry": (
            "campaign",
            "tension",
            "campaign_x_tension",
            "frequency",
            "stroke",
        ),
        "ln(backlash.gap)": ("campaign", "tension", "stroke"),
        "ln(backlash.drag/Fs)": ("campaign", "tension"),
        # the shape: what the records determine (chi sits at its bound on most records)
        "log_phi_max": ("campaign", "tension", "campaign_x_tension"),
        "log1p_beta": ("campaign",),
        "chi": (),
    },
}
#: the same, with the slip force's curvature in tension as ln(1 + tension/lb) per campaign
#: instead of a square (a saturating form, as the capstan-like grip of a band might give)
LAW_SETS["campaign_log"] = dict(
    LAW_SETS["campaign"],
    Fs=(
        "campaign",
        "tension",
        "campaign_x_tension",
        "ln1p_tension",
        "campaign_x_ln1p_tension",
        "frequency",
        "stroke",
    ),
)


def _derived(c):
    """The derived conditions the law sets use (products and squares of the nominal ones)."""
    c = dict(c)
    c["campaign_x_tension"] = c["campaign"] * c["tension"]
    c["tension_squared"] = c["tension"] ** 2
    c["campaign_x_tension_squared"] = c["campaign"] * c["tension"] ** 2
    c["ln1p_tension"] = float(np.log1p(c["tension"]))
    c["campaign_x_ln1p_tension"] = c["campaign"] * c["ln1p_tension"]
    return c


def _diagnose(path, lowpass, cache):
    from iwan_element import diagnose

    pkl = None if cache is None else Path(cache) / (path.stem + ".pkl")
    if pkl is not None and pkl.exists():
        return pickle.loads(pkl.read_bytes()), 0.0
    t, u, F = np.loadtxt(path, delimiter=",", skiprows=1).T
    t0 = time.perf_counter()
    d = diagnose(t, u, F, lowpass=lowpass)
    if pkl is not None:
        pkl.parent.mkdir(parents=True, exist_ok=True)
        pkl.write_bytes(pickle.dumps(d))
    return d, time.perf_counter() - t0


def real(args):
    from iwan_element import fit_campaign

    shared = next(
        (
            p / "shared" / "data"
            for p in (ROOT.parent, ROOT.parent.parent)
            if (p / "shared" / "data").is_dir()
        ),
        None,
    )
    if shared is None:
        print("../shared/data is absent (CC BY-SA 4.0 damper records): skipped")
        return
    files = sorted(shared.glob("arts-damper/ds1_*.csv")) + sorted(
        shared.glob("arts-damper-ds2/ds2_*.csv")
    )
    recs = [tuple(np.loadtxt(p, delimiter=",", skiprows=1).T) for p in files]
    laws = LAW_SETS[args.laws]
    conds = [
        _conditions(p, args.stroke or laws is not None, args.interaction, args.quadratic)
        for p in files
    ]
    if laws is not None:
        conds = [_derived(c) for c in conds]
    t0 = time.perf_counter()
    with ProcessPoolExecutor(args.jobs) as ex:
        out = list(ex.map(_diagnose, files, [args.lowpass] * len(files), [args.cache] * len(files)))
    diags = [d for d, _ in out]
    print(
        f"per-record diagnoses: {time.perf_counter() - t0:.0f} s wall "
        f"({sum(s for _, s in out):.0f} s computed now, the rest from --cache)"
    )
    fit = fit_campaign(
        recs,
        conds,
        names=[p.stem for p in files],
        diagnoses=diags,
        lowpass=args.lowpass,
        max_nfev=args.max_nfev,
        laws=laws,
        effects=args.effects.split(",") if args.effects else None,
    )
    print(fit.report())
    if args.attribute:
        attribute(fit)
    if args.neighbours:
        neighbours(fit)
    t1 = time.perf_counter()
    loo = fit.leave_one_out(refit=args.loo, jobs=args.jobs, coverage=args.band)
    print(loo.report())
    print(
        f"leave-one-out: {time.perf_counter() - t1:.0f} s; "
        f"{sum(r['ratio'] <= 1.5 for r in loo.rows)}/{len(loo.rows)} records within 1.5x"
    )


#: Quantity groups of ``--attribute``: the slip force, the joint's shape, the asymmetry,
#: the backlash (each group swapped as a whole: its members compensate one another).
GROUPS = {
    "Fs": ("Fs",),
    "shape": ("log_phi_max", "chi", "log1p_beta"),
    "asymmetry": ("asymmetric_slip.asymmetry",),
    "backlash": ("ln(backlash.gap)", "ln(backlash.drag/Fs)"),
}


def attribute(fit):
    """Per record, what part of the campaign model's band misfit comes from which quantity:
    the band misfit (over the record's own fit's) of the device at the laws, at the record's
    own values with the campaign stack (``free``), and with one group swapped: the laws with
    the record's own values of that group (``law+own``) and the record's own values with the
    laws' values of that group (``own+law``). Nuisances (offset, start) fitted as in the
    leave-one-out.
    """
    from iwan_element.diagnose.campaign.predict import predict_record

    st = fit._state
    model, theta, preps, free = st["model"], st["theta"], st["preps"], st["free"]
    groups = {g: [q for q in qs if q in model.qnames] for g, qs in GROUPS.items()}
    groups = {g: qs for g, qs in groups.items() if qs}
    head = "  ".join(f"{g[:9]:>9}" for g in groups)
    print(
        f"attribution (band misfit / own fit's): {'record':<24} {'laws':>5} {'free':>5}  "
        f"law+own: {head}  own+law: {head}"
    )
    counts = {}
    for r, p in enumerate(preps):
        own, law = p["band_own"], model.law_values(theta, model.X[r])
        f = free[r] if free[r] is not None else law

        def ratio(vals, r=r, p=p, own=own):
            return predict_record(model, theta, r, p, vals=vals)[0] / own

        out = {"laws": ratio(law), "free": ratio(dict(f))}
        for g, qs in groups.items():
            out[f"law+own {g}"] = ratio(dict(law, **{q: f[q] for q in qs}))
            out[f"own+law {g}"] = ratio(dict(f, **{q: law[q] for q in qs}))
        for k, v in out.items():
            counts[k] = counts.get(k, 0) + (v <= 1.5)
        vals = list(out.values())
        print(
            f"  {fit.records[r]:<24} {vals[0]:5.2f} {vals[1]:5.2f}  law+own: "
            + "  ".join(f"{v:9.2f}" for v in vals[2::2])
            + "  own+law: "
            + "  ".join(f"{v:9.2f}" for v in vals[3::2])
        )
    print("records within 1.5x: " + ", ".join(f"{k} {v}" for k, v in counts.items()))


def neighbours(fit):
    """What the nominal conditions can predict at best, with no law at all: each record
    predicted from the median of the own values (campaign stack) of the other records of
    the same campaign and band tension (``same T``), and of those among them nearest in
    frequency, then in stroke (``nearest``). Band misfit over the record's own fit's.
    """
    import math

    from iwan_element.diagnose.campaign.predict import predict_record

    st = fit._state
    model, theta, preps, free = st["model"], st["theta"], st["preps"], st["free"]
    col = {c: j for j, c in enumerate(model.cnames)}
    X = model.X

    def key(r):
        return X[r, col["campaign"]], X[r, col["tension"]]

    def dist(r, k):
        return tuple(abs(X[r, col[c]] - X[k, col[c]]) for c in ("frequency", "stroke") if c in col)

    counts, n = {"same T": 0, "nearest": 0}, len(preps)
    for r in range(n):
        grp = [k for k in range(n) if k != r and key(k) == key(r) and free[k] is not None]
        near = [k for k in grp if dist(r, k) == min(dist(r, j) for j in grp)] if grp else []
        out = []
        for name, g in (("same T", grp), ("nearest", near)):
            if not g:
                out.append(math.nan)
                continue
            vals = {q: float(np.median([free[k][q] for k in g])) for q in model.qnames}
            out.append(
                predict_record(model, theta, r, preps[r], vals=vals)[0] / preps[r]["band_own"]
            )
            counts[name] += out[-1] <= 1.5
        print(
            f"  neighbours {fit.records[r]:<24} same T ({len(grp)}) {out[0]:5.2f}   "
            f"nearest ({len(near)}) {out[1]:5.2f}"
        )
    print(
        f"neighbours: within 1.5x: same campaign and tension {counts['same T']}/{n}, "
        f"nearest of those {counts['nearest']}/{n}"
    )


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--coverage", type=int, default=0, help="synthetic campaigns")
    ap.add_argument(
        "--fs-scatter",
        type=float,
        default=0.0,
        dest="fs_scatter",
        help="--coverage: campaigns whose records' Fs scatter by this (ln Fs sd)",
    )
    ap.add_argument("--real", action="store_true", help="the 29 real damper records")
    ap.add_argument("--stroke", action="store_true", help="nominal stroke as a condition")
    ap.add_argument(
        "--interaction",
        action="store_true",
        help="campaign x tension as a condition (a tension slope per campaign)",
    )
    ap.add_argument("--quadratic", action="store_true", help="tension squared as a condition")
    ap.add_argument(
        "--effects",
        default=None,
        help="the campaign's stack, comma-separated (default: named on >= half)",
    )
    ap.add_argument(
        "--laws",
        default="linear",
        choices=sorted(LAW_SETS),
        help="law set: 'linear' (every quantity in every condition), 'campaign' "
        "(per-campaign laws chosen with the physics) or 'campaign_log' "
        "(the same, Fs curved in ln(1 + tension))",
    )
    ap.add_argument(
        "--attribute",
        action="store_true",
        help="per record, the part of the campaign misfit each quantity makes",
    )
    ap.add_argument(
        "--neighbours",
        action="store_true",
        help="predict each record from the records of the same campaign and "
        "tension (no law): what the nominal conditions can give at best",
    )
    ap.add_argument("--lowpass", type=float, default=20.0)
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--cache", default=None, help="folder of cached per-record diagnoses")
    ap.add_argument("--loo", default="step", choices=("step", "full"))
    ap.add_argument(
        "--band",
        action="store_true",
        help="leave-one-out: coverage of each left-out record's band samples by "
        "the 95 %% prediction band, with and without the record scatter",
    )
    ap.add_argument("--max-nfev", type=int, default=100, dest="max_nfev")
    args = ap.parse_args(argv)
    if args.coverage:
        coverage(args.coverage, args.fs_scatter)
    if args.real:
        real(args)
    if not (args.coverage or args.real):
        ap.print_help()
    return 0


if __name__ == "__main__":
    sys.exit(main())
