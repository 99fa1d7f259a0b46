"""The diagnosis' probabilities on the real records, against today's yes/no answer.

* every ARTS friction-damper record (``../shared/data/arts-damper`` and
  ``arts-damper-ds2``, CC BY-SA 4.0; ``diagnose(..., lowpass=20)``): the stepwise rule's
  answer (``details["rule_named"]``), the most probable explanation (what is named) with its
  probability, the next explanations, each effect's marginal probability, and the process
  CPU time of the diagnosis with and without the probabilities
  (``probabilities=False``: today's cost);
* the Brake-Reuss beam's force-controlled stepped-sine sweeps (``../shared/data/
  brb-steppedsine-fc``, GPL-3.0, read in place, never copied) against the beam model's
  QSMA (``models.preset("brake-reuss")``, as ``examples/brb_discrepancy.py``, with
  ``between_tests=True``).

    nice -n 10 python benchmarks/bench_real_probabilities.py [--jobs 2] [--only arts|brb]
        [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def shared(name):
    for p in (ROOT.parent, ROOT.parent.parent, Path.cwd().parent):
        d = p / "shared" / "data" / name
        if d.is_dir():
            return d
    return None


def _rows(d, top=3):
    return [(" + ".join(e.effects) or "plain", float(e.probability)) for e in d.explanations[:top]]


def run_record(path):
    from iwan_element import diagnose

    t, u, F = np.loadtxt(path, delimiter=",", skiprows=1).T
    c0 = time.process_time()
    d = diagnose(t, u, F, lowpass=20.0)
    cpu = time.process_time() - c0
    c0 = time.process_time()
    g = diagnose(t, u, F, lowpass=20.0, probabilities=False)
    cpu0 = time.process_time() - c0
    effs = sorted({n for e in d.explanations for n in e.effects})
    return {
        "record": path.stem,
        "rule": " + ".join(d.details["rule_named"]) or "none",
        "rule_without": " + ".join(g.effects) or "none",
        "named": " + ".join(d.effects) or "none",
        "top": _rows(d),
        "effects": {n: d.effect_probability(n) for n in effs},
        "cpu": cpu,
        "cpu_without": cpu0,
        "explanations": len(d.explanations),
    }


def run_brb():
    import iwan_element as ie
    from iwan_element import models

    d = shared("brb-steppedsine-fc")
    if d is None:
        return None
    a = np.loadtxt(d / "fc_sweeps.csv", delimiter=",", skiprows=1)
    level, f, F, A, phase = a.T
    sweeps = ie.sweep_curve(f, F, A, phase, level=level.astype(int), quantity="acceleration")
    spec = models.preset("brake-reuss")
    before = models.modal_amplitude_curve(spec, amplitude=sweeps.amplitude)
    c0 = time.process_time()
    g = ie.diagnose_vibration(
        sweeps,
        predicted_frequency=before.frequency,
        predicted_damping_ratio=before.damping_ratio,
        predicted_zeta0=spec.interface.damping_floor,
        between_tests=True,
    )
    cpu = time.process_time() - c0
    effs = sorted({n for e in g.explanations for n in e.effects})
    return {
        "record": "brb fc_sweeps (4 levels)",
        "rule": " + ".join(g.details["rule_named"]) or "none",
        "named": " + ".join(g.effects) or "none",
        "top": _rows(g, 4),
        "effects": {n: g.effect_probability(n) for n in effs},
        "cpu": cpu,
        "report": g.report(),
    }


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--only", choices=("arts", "brb"))
    ap.add_argument("--json", type=Path)
    a = ap.parse_args(argv)
    out = {}
    if a.only != "brb":
        files = [
            p
            for name in ("arts-damper", "arts-damper-ds2")
            if shared(name)
            for p in sorted(shared(name).glob("*.csv"))
        ]
        if not files:
            print("../shared/data/arts-damper* absent: skipped")
        if a.jobs == 1:
            rows = [run_record(f) for f in files]
        else:
            with ProcessPoolExecutor(a.jobs) as ex:
                rows = list(ex.map(run_record, files))
        out["arts"] = rows
        print(f"{'record':<24} {'rule (yes/no)':<36} {'most probable (p)':<44} next")
        for r in rows:
            (n0, p0), rest = r["top"][0], r["top"][1:]
            flag = "" if r["rule"] == r["named"] else "   <- differs"
            print(
                f"{r['record']:<24} {r['rule']:<36} {n0 + f' ({p0:.3g})':<44} "
                + ", ".join(f"{n} {p:.2g}" for n, p in rest)
                + flag
            )
        cpu, cpu0 = np.array([r["cpu"] for r in rows]), np.array([r["cpu_without"] for r in rows])
        diff = [r for r in rows if r["rule"] != r["named"]]
        print(
            f"\n{len(rows)} records; the most probable explanation differs from the rule's "
            f"answer on {len(diff)}; below 0.9 on "
            f"{sum(r['top'][0][1] <= 0.9 for r in rows)}"
        )
        print(
            f"CPU per record: with probabilities median {np.median(cpu):.1f} s (max "
            f"{cpu.max():.1f}), without {np.median(cpu0):.1f} s (max {cpu0.max():.1f}); "
            f"total ratio {cpu.sum() / cpu0.sum():.2f}"
        )
    if a.only != "arts":
        b = run_brb()
        out["brb"] = b
        if b is None:
            print("../shared/data/brb-steppedsine-fc absent: skipped")
        else:
            print(
                f"\n{b['record']}: rule {b['rule']}, named {b['named']}; "
                + ", ".join(f"{n} {p:.3g}" for n, p in b["top"])
                + f"; CPU {b['cpu']:.2f} s"
            )
            print(b["report"])
    if a.json:
        a.json.write_text(json.dumps(out, indent=1, default=float))
    return 0


if __name__ == "__main__":
    sys.exit(main())
