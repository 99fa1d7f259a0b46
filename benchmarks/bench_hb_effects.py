"""Harmonic balance on the Brake-Reuss beam with and without the sweeps' named effects.

Run:  PYTHONPATH=examples python benchmarks/bench_hb_effects.py [--repeat 3] [--json PATH]
      [--no-stepped]

The plain preset (``models.preset("brake-reuss")``) and the sweeps-augmented one (the
force-controlled sweeps diagnosed against the preset's QSMA with the between-test nuisances,
then ``diag.augment(spec)``, as ``examples/brb_discrepancy.py`` builds it: the effects in
the joint, beside each contact point's Iwan element) solve each measured 41-point level
(79.2-81.2 Hz, the recorded force at each point; harmonics 1, 3, 5, 8 kept modes, as
``examples/brb_stepped_sine.py``) after a warm-up (numba compilation, the reduced models).
``augmented`` runs the effects in the joint (``joint_forms``: each point's stack in the
compiled kernel, exact Jacobian); ``modal`` the same fit in its modal form
(``diag.augment(spec, form="modal")``: one element port on mode 1, compiled), and
``stepped`` that modal system with the port's element hidden behind a wrapper that does not
state its periodic form, so the AFT steps the effect elements sample by sample in Python
with a forward-difference Jacobian (the route every port took before).
Printed per level and model: the best of ``--repeat`` wall times [s], Newton iterations,
the rms of ``log(predicted / measured X)`` and the rms phase error [rad] against the
records, and the largest energy error per period; then the largest amplitude difference
between the compiled and stepped routes of the modal form.

Data (GPL-3.0, read from ``../shared`` only, never copied): ``brb-steppedsine-fc/
fc_sweeps.csv`` (Chen et al., MSSP 166:108401, 2022; Jin et al., MSSP 166:108402, 2022).
"""

from __future__ import annotations

import argparse
import json
import math
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
from brb_discrepancy import data_dir, diagnose_sweeps, sweeps_curve
from brb_stepped_sine import HARMONICS, N_MODES, read_levels
from iwan_element.models.modal.frequency import specimen_system

from iwan_element import models
from iwan_element.harmonic import harmonic_balance
from iwan_element.harmonic.system import ElementPort


class Stepped:
    """An element without its periodic form (every other attribute its own): the AFT then
    steps it sample by sample.
    """

    def __init__(self, element):
        self.element = element

    def __getattr__(self, name):
        if name == "periodic_form":
            raise AttributeError(name)
        return getattr(self.element, name)


def stepped_system(spec):
    """The specimen's modal system with its ports' elements behind :class:`Stepped`."""
    s = specimen_system(spec, n_modes=N_MODES)
    ports = tuple(ElementPort(Stepped(p.element), p.gain, p.label) for p in s.ports)
    return replace(s, ports=ports)


def _solve(spec, f, F):
    if spec[0] == "stepped":
        return harmonic_balance(spec[1], frequency=f, force=F, harmonics=HARMONICS)
    return models.harmonic_balance(
        spec[1], frequency=f, force=F, harmonics=HARMONICS, n_modes=N_MODES
    )


def _level(spec, f, F, X, ph, repeat):
    """Best wall and CPU times of ``repeat`` solves of one level, and the last solve's
    errors.
    """
    best = cpu = math.inf
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        r = _solve(spec, f, F)
        best = min(best, time.perf_counter() - t0)
        cpu = min(cpu, time.process_time() - c0)
    ok = r.converged
    e_amp = np.log(r.amplitude[ok] / X[ok])
    e_ph = np.angle(np.exp(1j * (r.phase[ok] - ph[ok])))
    return {
        "wall": best,
        "cpu": cpu,
        "newton": int(r.iterations.sum()),
        "converged": int(ok.sum()),
        "rms_log_amplitude": float(np.sqrt(np.mean(e_amp**2))),
        "rms_phase": float(np.sqrt(np.mean(e_ph**2))),
        "max_energy_error": float(np.nanmax(np.abs(r.energy_error))),
        "amplitude": r.amplitude.tolist(),
    }


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3, help="timed solves per level (best kept)")
    ap.add_argument("--json", type=Path, default=None, help="write the figures here")
    ap.add_argument("--no-stepped", action="store_true", help="leave the stepped route out")
    a = ap.parse_args(argv)
    d = data_dir()
    if d is None:
        print("../shared/data/brb-steppedsine-fc (GPL data, read in place) not found")
        return 0
    path = d / "brb-steppedsine-fc" / "fc_sweeps.csv"
    spec = models.preset("brake-reuss")
    _, diag = diagnose_sweeps(spec, sweeps_curve(path))
    aug = models.resolve_interface_effects(diag.augment(spec))
    modal = diag.augment(spec, form="modal")
    specs = {
        "plain": ("models", spec),
        "augmented": ("models", aug),
        "modal": ("models", modal),
        "stepped": ("stepped", stepped_system(modal)),
    }
    if a.no_stepped:
        del specs["stepped"]
    print(f"augmented: + {' + '.join(diag.effects)}")
    levels = read_levels(path)
    for s in specs.values():  # warm-up: compile, reduce
        f, F, _, _ = levels[1]
        _solve(s, f[:3], F[:3])
    out = {}
    print(
        f"{'level':>5} {'model':>10} {'wall [s]':>9} {'cpu [s]':>8} {'Newton':>7} {'conv':>5} "
        f"{'rms log X':>10} {'rms ph':>8} {'energy err':>11}"
    )
    for lev, (f, F, X, ph) in levels.items():
        for name, s in specs.items():
            row = _level(s, f, F, X, ph, a.repeat)
            out[f"{lev}/{name}"] = row
            print(
                f"{lev:5d} {name:>10} {row['wall']:9.3f} {row['cpu']:8.3f} {row['newton']:7d} "
                f"{row['converged']:5d} {row['rms_log_amplitude']:10.4f} "
                f"{row['rms_phase']:8.4f} {row['max_energy_error']:11.1e}"
            )
    for name in specs:
        w = [out[f"{k}/{name}"]["wall"] for k in levels]
        c = [out[f"{k}/{name}"]["cpu"] for k in levels]
        print(
            f"{name:>10}: mean {np.mean(w):.3f} s wall, {np.mean(c):.3f} s cpu a 41-point "
            f"level (max {max(w):.3f} s wall)"
        )
    if not a.no_stepped:
        dx = max(
            np.max(
                np.abs(
                    np.divide(out[f"{k}/modal"]["amplitude"], out[f"{k}/stepped"]["amplitude"]) - 1
                )
            )
            for k in levels
        )
        print(
            f"modal form, compiled against stepped: largest relative amplitude difference {dx:.1e}"
        )
    if a.json is not None:
        a.json.write_text(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
