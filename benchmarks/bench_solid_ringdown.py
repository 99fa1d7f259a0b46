"""The Brake-Reuss solid's Exudyn ring-down: cost against linear springs, energy, QSMA.

Run:  python benchmarks/bench_solid_ringdown.py [--mesh 0.012 0.008] [--patch 0.0064]
      [--modes 20] [--duration 0.5]

For each mesh size the solid is built as in ``benchmarks/bench_solid.py`` (lap faces at 0.6 x
the patch size, ``--modes`` stuck modes + 3 attachment shapes per patch) and released
(``models.ringdown``, 64 steps per period of the highest released mode, ``--duration`` s):

* in mode 1 (first height bending) from 60 um at the sensor;
* in modes 1 and 3 together (the solid's stuck mode 3 is the second height bending; its
  mode 2 is the in-plane bending, which the sensor's z displacement does not see) from 60
  and 20 um.

Each release runs twice with the Iwan elements (without and with the energy records) and
once with linear springs at the stuck stiffness on the same bodies (``tangential="linear"``).
Printed per run: wall time in ``SolveDynamic``, ms per step, Newton iterations per step,
Jacobians computed, and the largest energy-balance error; for mode 1 the ring-down's
frequency and damping against the solid's QSMA curve at the same amplitudes (independent
routes). Last, the solver: the mode-1 Iwan run with Exudyn's sparse solver instead of the
dense one the ring-down uses, and with full Newton instead of modified Newton.
"""

from __future__ import annotations

import argparse
import time

import exudyn as exu
import numpy as np
from iwan_element.models import modal_amplitude_curve, preset, ringdown
from iwan_element.models.modal import static_modal_load
from iwan_element.models.simulation import build_host, solver_settings
from iwan_element.models.solid import lap_beam_parts, solid_specimen


def _cost(label, r):
    m = r.metadata
    err = r.max_energy_error
    print(
        f"  {label:<34s} {m['steps']:6d} steps {r.wall_time:7.2f} s "
        f"{1e3 * r.wall_time / m['steps']:6.3f} ms/step, "
        f"Newton {m['newton_iterations'] / m['steps']:.2f}/step, {m['jacobians']} Jacobian(s)"
        + ("" if err is None else f", energy error {err:.1e}")
    )


def _qsma(solid, r):
    c = r.curve
    q = modal_amplitude_curve(solid, amplitude=c.amplitude)
    df = c.frequency / q.frequency - 1
    dz = c.damping_ratio / q.damping_ratio - 1
    print(
        f"  mode 1 vs QSMA ({len(c)} points, {c.amplitude.min() * 1e6:.1f}-"
        f"{c.amplitude.max() * 1e6:.1f} um): frequency {c.frequency.max():.4f}-"
        f"{c.frequency.min():.4f} Hz, off by {np.abs(df).max():.1e}; damping "
        f"{100 * c.damping_ratio.min():.4f}-{100 * c.damping_ratio.max():.4f} %, off by "
        f"{100 * np.abs(dz).max():.2f} %"
    )


def _solvers(solid, duration):
    """The mode-1 Iwan release on the same model with Exudyn's sparse solver (its default)
    and with full Newton (a Jacobian per iteration; over a tenth of the duration).
    """
    st = static_modal_load(solid, [60e-6], mode=1)
    out = {}
    for name, kind, modified, dur in (
        ("dense", exu.LinearSolverType.EigenDense, True, duration),
        ("sparse", exu.LinearSolverType.EigenSparse, True, duration),
        ("dense, full Newton", exu.LinearSolverType.EigenDense, False, 0.1 * duration),
    ):
        model = build_host(solid)
        model.set_state(st["x"][0])
        h = 2 * np.pi / (st["omega0"] * 64)
        n = int(round(dur / h))
        z0 = model.T_inv @ st["x"][0]
        sim = solver_settings(force_scale=float(np.max(np.abs((model.Kb + model.Ks) @ z0))))
        sim.linearSolver.solverType = kind
        sim.timeIntegration.newton.useModifiedNewton = modified
        sim.timeIntegration.numberOfSteps = n
        sim.timeIntegration.endTime = n * h
        t0 = time.perf_counter()
        model.mbs.SolveDynamic(sim)
        it = model.mbs.sys["dynamicSolver"].it
        out[name] = (
            1e3 * (time.perf_counter() - t0) / n,
            it.newtonStepsCount / n,
            it.newtonJacobiCount / n,
        )
    print(
        "  mode 1 Iwan, solver variants: "
        + "; ".join(
            f"{k} {v[0]:.3f} ms/step ({v[1]:.2f} iterations, {v[2]:.2f} Jacobians per step)"
            for k, v in out.items()
        )
    )


def run(mesh, patch, modes, duration):
    s = preset("brake-reuss")
    t0 = time.perf_counter()
    parts = lap_beam_parts(s, mesh_size=mesh, lap_mesh_size=0.6 * patch)
    t_mesh = time.perf_counter() - t0
    solid = solid_specimen(s, parts, patch_size=patch, n_modes=modes)
    info = solid.model.info
    print(
        f"mesh {mesh * 1e3:.1f} mm: {info['n_full']} coordinates -> {info['n_reduced']} "
        f"({info['n_patches']} patches, {2 * info['n_patches']} Iwan elements); meshing "
        f"{t_mesh:.1f} s, reduction {info['reduction_s']:.1f} s; {duration} s ring-downs:"
    )
    for label, amp in (
        ("mode 1, 60 um", {1: 60e-6}),
        ("modes 1 + 3, 60 + 20 um", {1: 60e-6, 3: 20e-6}),
    ):
        kw = {"amplitude": amp, "duration": duration, "steps_per_period": 64}
        r = ringdown(solid, **kw)
        _cost(f"{label}, Iwan", r)
        _cost(f"{label}, Iwan, energy recorded", ringdown(solid, record_energy=True, **kw))
        _cost(f"{label}, linear springs", ringdown(solid, tangential="linear", **kw))
        if len(amp) == 1:
            _qsma(solid, r)
        else:
            for mode, c in zip(r.modes, r.curves):
                print(
                    f"  mode {mode}: {len(c)} points, f {c.frequency.min():.3f}-"
                    f"{c.frequency.max():.3f} Hz, zeta {100 * c.damping_ratio.min():.4f}-"
                    f"{100 * c.damping_ratio.max():.4f} %"
                )
    _solvers(solid, duration)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mesh", type=float, nargs="+", default=[0.012, 0.008])
    ap.add_argument("--patch", type=float, default=0.0064)
    ap.add_argument("--modes", type=int, default=20)
    ap.add_argument("--duration", type=float, default=0.5)
    a = ap.parse_args()
    for m in a.mesh:
        run(m, a.patch, a.modes, a.duration)


if __name__ == "__main__":
    main()
