"""Harmonic balance against a peer: pyHarm-os's Jenkins element on a one-dof oscillator.

Run (the peer lives in its own virtual environment, ``pip install iwan-element[peer]`` or
``python -m venv --system-site-packages VENV && VENV/bin/pip install pyharm-os``)::

    PYTHONPATH=. VENV/bin/python benchmarks/bench_hb_peer.py [--markdown]

Without pyharm-os the script runs this package's side alone and says the peer is absent.

The system is ``m x'' + c x' + k x + F_J(x) = F cos(2 pi f t)`` with one Jenkins element
``F_J`` (spring ``KT`` in series with a Coulomb slider of slip force ``Fs``), forced through
its stick-slip resonance (stuck near 63.7 Hz, fully slipped 31.8 Hz) at a few force levels:

* **ours**: :func:`iwan_element.harmonic.harmonic_balance` on
  :meth:`~iwan_element.harmonic.ModalSystem.oscillator` with the Jenkins element as the
  one-slider limit of Segalman's four-parameter Iwan, ``IwanParameters(Fs, KT, chi, beta)``
  with a very large ``beta`` (all but ``1/(1+beta)`` of the stiffness in the slider at
  ``phi_max -> Fs/KT``). The limit is checked first against the closed-form Jenkins element
  (a spring ``KT`` whose force saturates at ``+-Fs``, stepped as a play operator) on virgin
  loading and on the steady loop the harmonic balance uses; the residual is printed.
* **peer**: pyHarm-os (Apache-2.0, https://gitlab.com/drti/pyharm) with its ``Jenkins``
  connector (``mu N0 = Fs``, ``k = KT``), mass (``GOElement``, second time derivative), linear
  spring and damper and ``CosinusForcing``; its Newton-Raphson solver with the no-continuation
  corrector solves one frequency at a time.

Both sides use the same harmonics, the same number of time samples per period, the same
frequencies in the same order and the same start (the previous converged point, else the
linear response), Newton's method with a relative tolerance of about 1e-9, and one BLAS
thread. Each sweep is run once untimed (compilation and caches) and then ``--repeat`` times;
the best wall time is reported (``cold`` is the first sweep, building the peer's model
included). Amplitudes are the fundamental displacement amplitudes; they must agree within
``--rtol`` (1 %) wherever both converge, or the script exits with status 1.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import logging
import math
import os
import sys
import tempfile
import time
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from iwan_element import IwanParameters  # noqa: E402
from iwan_element.core.masing import masing_constants, masing_history  # noqa: E402
from iwan_element.core.periodic import periodic_rows  # noqa: E402
from iwan_element.harmonic import ModalSystem, harmonic_balance  # noqa: E402


@dataclass(frozen=True)
class Case:
    """The oscillator, the sweep and the numerics shared by both sides."""

    mass: float  # [kg]
    stiffness: float  # linear spring in parallel [N/m]
    damping: float  # dashpot [N s/m]
    KT: float  # Jenkins spring [N/m]
    Fs: float  # Jenkins slip force [N]
    beta: float  # the Iwan's spike ratio used for the one-slider limit [-]
    frequency: np.ndarray  # [Hz]
    forces: tuple  # force amplitudes [N]
    harmonics: tuple
    samples: int
    tol: float  # Newton's relative tolerance
    max_iter: int

    @property
    def joint(self) -> IwanParameters:
        return IwanParameters(self.Fs, self.KT, 0.0, self.beta)


def parse(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--forces",
        type=float,
        nargs="+",
        default=[1.0, 3.0, 10.0],
        help="force amplitudes [N] (default 1 3 10)",
    )
    ap.add_argument("--band", type=float, nargs=2, default=[25.0, 75.0], help="[Hz]")
    ap.add_argument("--points", type=int, default=51, help="frequencies in the band")
    ap.add_argument("--harmonics", type=int, nargs="+", default=[1, 3, 5])
    ap.add_argument("--samples", type=int, default=64, help="time samples per period")
    ap.add_argument(
        "--beta",
        type=float,
        default=1e6,
        help="spike ratio of the Iwan's one-slider limit (default 1e6)",
    )
    ap.add_argument("--repeat", type=int, default=3, help="timed sweeps per side")
    ap.add_argument("--rtol", type=float, default=0.01, help="amplitude agreement required")
    ap.add_argument("--markdown", action="store_true", help="print the table as markdown")
    args = ap.parse_args(argv)
    case = Case(
        mass=1.0,
        stiffness=4.0e4,
        damping=8.0,
        KT=1.2e5,
        Fs=10.0,
        beta=args.beta,
        frequency=np.linspace(args.band[0], args.band[1], args.points),
        forces=tuple(args.forces),
        harmonics=tuple(sorted(set(args.harmonics))),
        samples=args.samples,
        tol=1e-9,
        max_iter=40,
    )
    return args, case


# ---------------------------------------------------------------- the one-slider limit
def jenkins_closed_form(u, KT, Fs):
    """Force [N] of the Jenkins element along the sampled path ``u`` [m] from the relaxed
    state: ``KT (u - z)``, the slider ``z`` moving only to keep ``|KT (u - z)| <= Fs``.
    """
    phi = Fs / KT
    z = 0.0
    out = np.empty(len(u))
    for i, x in enumerate(u):
        z = min(max(z, x - phi), x + phi)
        out[i] = KT * (x - z)
    return out


def jenkins_limit(case: Case, levels=(0.5, 0.999, 2.0, 5.0)):
    """Largest ``|F_iwan - F_jenkins| / Fs`` over virgin-plus-cyclic histories
    (:func:`~iwan_element.core.masing.masing_history`) and over the steady loops of the
    harmonic balance's kernel (:func:`~iwan_element.core.periodic.periodic_rows`), at
    amplitudes ``levels * Fs/KT``.
    """
    p = case.joint
    phi = case.Fs / case.KT
    tau = 2 * np.pi * np.arange(case.samples) / case.samples
    hist = per = 0.0
    for a in levels:
        u = a * phi * np.sin(np.linspace(0.0, 6 * np.pi, 3001))
        hist = max(
            hist,
            float(
                np.max(np.abs(masing_history(u, p)[0] - jenkins_closed_form(u, case.KT, case.Fs)))
            ),
        )
        # a periodic slip with a third harmonic (inner reversals when a is large enough)
        up = a * phi * (np.cos(tau) + 0.3 * np.cos(3 * tau + 0.4))
        F, _, _, _ = periodic_rows(masing_constants(p, 0.0)[None, :], up[None, :])
        ref = jenkins_closed_form(np.tile(up, 3), case.KT, case.Fs)[-case.samples :]
        per = max(per, float(np.max(np.abs(F[0] - ref))))
    return hist / case.Fs, per / case.Fs


# ---------------------------------------------------------------- our side
def run_ours(case: Case, force: float, repeat: int):
    system = ModalSystem.oscillator(case.mass, case.stiffness, case.damping, case.joint)

    def sweep():
        return harmonic_balance(
            system,
            frequency=case.frequency,
            force=force,
            harmonics=case.harmonics,
            samples=case.samples,
            tol=case.tol,
            max_iter=case.max_iter,
        )

    t0 = time.perf_counter()
    sweep()
    cold = time.perf_counter() - t0
    best, r = math.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        r = sweep()
        best = min(best, time.perf_counter() - t0)
    return {
        "amplitude": r.amplitude,
        "phase": r.phase,
        "converged": r.converged,
        "iterations": r.iterations,
        "wall": best,
        "cold": cold,
        "energy": float(np.max(np.abs(r.energy_error))),
    }


# ---------------------------------------------------------------- the peer
def peer_version():
    """pyHarm-os's version, or None when it is not installed. pyHarm keeps a state file
    under the working directory unless told otherwise: it goes to the temporary folder.
    """
    os.environ.setdefault(
        "PYHARM_CONTEXT_FILE",
        str(Path(tempfile.gettempdir()) / "iwan-element-pyharm" / "context.json"),
    )
    try:
        from importlib.metadata import version

        import pyHarm  # noqa: F401

        return version("pyharm-os")
    except ImportError:
        return None


PEER_SOLVERS = ("hybr", "newton")


def peer_input(case: Case, force: float, solver: str) -> dict:
    """PyHarm's input dictionary of the oscillator (one substructure of one dof, grounded
    connectors) with a no-continuation frequency-response analysis. ``solver``: ``"hybr"``
    (pyHarm's default solver, scipy's ``root``) or ``"newton"`` (its Newton-Raphson).
    """
    node = {"connect": {"osc": [0]}, "dirs": [0]}
    W = 2 * np.pi * case.frequency
    phi = case.Fs / case.KT
    if solver == "newton":  # absolute tolerances [N] and [m]; ours is relative, 1e-9
        options = {
            "solver": "NewtonRaphson",
            "solver_options": {
                "tol_residual": case.tol * force,
                "tol_delta_x": case.tol * phi,
                "max_iter": case.max_iter,
            },
        }
    else:  # xtol: relative step, as ours
        options = {
            "solver": "scipyroot",
            "solver_options": {"root": {"method": "hybr", "options": {"xtol": case.tol}}},
        }
    return {
        "system": {"type": "Base", "nh": list(case.harmonics), "nti": case.samples},
        "substructures": {"osc": {"type": "onlydofs", "nnodes": 1, "ndofs": 1}},
        "connectors": {
            "mass": {"type": "GOElement", "dto": 2, "xo": 1, "k": case.mass, **node},
            "damper": {"type": "LinearDamper", "k": case.damping, **node},
            "spring": {"type": "LinearSpring", "k": case.stiffness, **node},
            "jenkins": {"type": "Jenkins", "mu": 1.0, "N0": case.Fs, "k": case.KT, **node},
            "force": {"type": "CosinusForcing", "amp": force, **node},
        },
        "analysis": {
            "frf": {
                "study": "frf",
                "puls_inf": W[0],
                "puls_sup": W[-1],
                "puls_start": W[0],
                "predictor": "previous",
                "corrector": "nocontinuation",
                "stepsizer": "constant",
                "verbose": False,
                **options,
            }
        },
    }


@contextlib.contextmanager
def quiet():
    """PyHarm logs a banner and per-step lines to stdout, and numba warns about array
    layouts in its elements: keep both out of the table.
    """
    with contextlib.redirect_stdout(io.StringIO()), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        logging.disable(logging.CRITICAL)
        try:
            yield
        finally:
            logging.disable(logging.NOTSET)


def _peer_sweep(analysis, W, index, rtol):
    """Solve every frequency in order from the previous converged point (else pyHarm's
    linear start), as :func:`harmonic_balance` does; fundamental coefficients out. A point
    counts as converged when its residual is below ``rtol`` [N], whatever the solver's status
    (pyHarm accepts any first point of its scipy route, and scipy's ``hybr`` may stop with
    "not making good progress" on a residual at round-off).
    """
    a1 = np.full(W.size, np.nan, complex)
    ok = np.zeros(W.size, bool)
    its = np.zeros(W.size, int)
    prev = None
    for k, w in enumerate(W):
        analysis.analysis_options["puls_start"] = w
        for x0 in [prev, None] if prev is not None else [None]:
            analysis.SolList = []
            analysis.initialise(x0)
            s = analysis.SolList[-1]
            good = float(np.linalg.norm(s.R_solver)) <= rtol
            if good:
                break
        its[k] = getattr(s, "iter_numb", 0)
        if good:
            ok[k] = True
            prev = s.x[:-1].copy()
            a1[k] = s.x[index[0]] - 1j * s.x[index[1]]
    return a1, ok, its


def run_peer(case: Case, force: float, repeat: int, solver: str):
    from pyHarm.Maestro import Maestro

    W = 2 * np.pi * case.frequency
    rtol = 10 * case.tol * force
    with quiet():
        t0 = time.perf_counter()
        maestro = Maestro(peer_input(case, force, solver))
        analysis = maestro.nls["frf"]
        edf = maestro.system._get_expl_dofs_into_solver()
        index = [int(edf.index[(edf["harm"] == 1) & (edf["cs"] == cs)][0]) for cs in "cs"]
        _peer_sweep(analysis, W, index, rtol)
        cold = time.perf_counter() - t0
        best = math.inf
        for _ in range(repeat):
            t0 = time.perf_counter()
            a1, ok, its = _peer_sweep(analysis, W, index, rtol)
            best = min(best, time.perf_counter() - t0)
    phase = np.angle(a1)
    phase[phase > 0.5 * math.pi] -= 2 * math.pi
    return {
        "amplitude": np.abs(a1),
        "phase": phase,
        "converged": ok,
        "iterations": its,
        "wall": best,
        "cold": cold,
    }


# ---------------------------------------------------------------- the tables
def _cell(fmt, v):
    if v is None:
        return "-"
    if isinstance(v, (bool, np.bool_)):
        return "yes" if v else "NO"
    return "-" if math.isnan(v) else fmt.format(v)


def _print(head, rows, markdown, width):
    if markdown:
        print("| " + " | ".join(head) + " |")
        print("|" + "---|" * len(head))
    else:
        print(" ".join(f"{h:>{width}}" for h in head))
    for cells in rows:
        print(
            "| " + " | ".join(cells) + " |"
            if markdown
            else " ".join(f"{c:>{width}}" for c in cells)
        )


def amplitude_rows(case: Case, force, ours, peers):
    """Table rows of one force level: frequency, force, our amplitude and convergence, and
    per peer solver its amplitude, relative difference and convergence.
    """
    rows = []
    for k, f in enumerate(case.frequency):
        cells = [
            f"{f:.2f}",
            f"{force:g}",
            _cell("{:.4f}", ours["amplitude"][k] * 1e6),
            _cell("", bool(ours["converged"][k])),
        ]
        for res in peers.values():
            ok = bool(res["converged"][k])
            rel = res["amplitude"][k] / ours["amplitude"][k] - 1.0 if ok else math.nan
            cells += [
                _cell("{:.4f}", res["amplitude"][k] * 1e6),
                _cell("{:+.1e}", rel),
                _cell("", ok),
            ]
        rows.append(cells)
    return rows


def agreement(ours, peers):
    """Per peer solver: (points both converged, largest |relative amplitude difference|,
    largest |phase difference| [rad]) over those points.
    """
    out = {}
    for name, res in peers.items():
        both = ours["converged"] & res["converged"]
        rel = np.abs(res["amplitude"][both] / ours["amplitude"][both] - 1.0)
        dph = np.abs(res["phase"][both] - ours["phase"][both])
        out[name] = (
            int(both.sum()),
            float(rel.max()) if rel.size else math.nan,
            float(dph.max()) if dph.size else math.nan,
        )
    return out


def time_rows(force, ours, peers, case: Case):
    n = case.frequency.size
    rows = [
        [
            f"{force:g}",
            "ours (Newton, exact Iwan kernel)",
            f"{ours['wall']:.4f}",
            f"{ours['cold']:.4f}",
            "1.0",
            f"{int(ours['iterations'].sum())}",
            f"{int(ours['converged'].sum())}/{n}",
            f"{ours['energy']:.1e}",
        ]
    ]
    for name, res in peers.items():
        rows.append(
            [
                f"{force:g}",
                f"pyHarm ({name})",
                f"{res['wall']:.4f}",
                f"{res['cold']:.4f}",
                f"{res['wall'] / ours['wall']:.1f}",
                f"{int(res['iterations'].sum())}" if name == "newton" else "-",
                f"{int(res['converged'].sum())}/{n}",
                "-",
            ]
        )
    return rows


def describe(case: Case, version):
    p = case.joint
    hist, per = jenkins_limit(case)
    print(
        f"oscillator: m = {case.mass} kg, k = {case.stiffness:g} N/m, c = {case.damping} N s/m;"
        f" Jenkins KT = {case.KT:g} N/m, Fs = {case.Fs} N (Fs/KT = "
        f"{case.Fs / case.KT * 1e6:.3f} um)"
    )
    print(
        f"stuck resonance {math.sqrt((case.stiffness + case.KT) / case.mass) / 2 / math.pi:.2f}"
        f" Hz, slipped {math.sqrt(case.stiffness / case.mass) / 2 / math.pi:.2f} Hz; "
        f"harmonics {case.harmonics}, {case.samples} samples per period, "
        f"{case.frequency.size} frequencies {case.frequency[0]:g}-{case.frequency[-1]:g} Hz, "
        f"forces {case.forces} N"
    )
    print(
        f"Jenkins as Iwan(Fs, KT, chi=0, beta={case.beta:g}): phi_max/(Fs/KT) - 1 = "
        f"{p.phi_max * case.KT / case.Fs - 1:.2e}; max |F_iwan - F_jenkins|/Fs = {hist:.2e} "
        f"(histories), {per:.2e} (steady loops of the harmonic balance's kernel)"
    )
    print(
        "peer: pyharm-os is not installed (pip install iwan-element[peer], in a separate "
        "environment): this package's side only"
        if version is None
        else f"peer: pyharm-os {version}"
    )


def main(argv=None) -> int:
    args, case = parse(argv)
    version = peer_version()
    describe(case, version)
    solvers = PEER_SOLVERS if version is not None else ()
    amp, times, agree = [], [], []
    with threadpool_limits(limits=1):
        for force in case.forces:
            ours = run_ours(case, force, args.repeat)
            peers = {s: run_peer(case, force, args.repeat, s) for s in solvers}
            amp += amplitude_rows(case, force, ours, peers)
            times += time_rows(force, ours, peers, case)
            agree.append(agreement(ours, peers))
    head = ["f [Hz]", "F [N]", "A ours [um]", "conv. ours"]
    for s in solvers:
        head += [f"A pyHarm {s} [um]", f"rel. diff {s}", f"conv. {s}"]
    print()
    _print(head, amp, args.markdown, 13)
    print()
    _print(
        [
            "F [N]",
            "route",
            "best [s]",
            "cold [s]",
            "/ ours",
            "iterations",
            "converged",
            "energy error",
        ],
        times,
        args.markdown,
        13,
    )
    print(
        f"\nwall times: whole sweeps of {case.frequency.size} frequencies, best of "
        f"{args.repeat}; cold: the first sweep (and building pyHarm's model); energy error:"
        " largest |input work - dissipation| / input work per period over the sweep"
    )
    ok = True
    for s in solvers:
        n = sum(a[s][0] for a in agree)
        rel = max((a[s][1] for a in agree if a[s][0]), default=math.nan)
        dph = max((a[s][2] for a in agree if a[s][0]), default=math.nan)
        print(
            f"pyHarm ({s}): both converged at {n} of {case.frequency.size * len(case.forces)} "
            f"points; largest |A_pyHarm/A_ours - 1| = {rel:.2e}, largest phase difference "
            f"{dph:.1e} rad (required: amplitudes within {args.rtol:g})"
        )
        ok &= n > 0 and rel < args.rtol
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
