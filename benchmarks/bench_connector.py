"""Cost of the Iwan connector in Exudyn, side by side with Exudyn's built-in linear connector.

One mass (1 kg) on a joint to ground (KT = 1e6 N/m, Fs = 1 kN, chi = -0.5, beta = 0.2),
free vibration from 3 m/s (macroslip first, then microslip), generalized-alpha with
Exudyn's default settings, fixed step 10 us, one thread, no solution file. Variants:

* ``builtin``      ObjectConnectorCoordinateSpringDamper, stiffness KT (the reference, 1.0)
* ``python-lin``   the same object with a Python user function returning ``k * deltaL``
* ``python-lin+post``    the same plus an empty post-step function
* ``python-nonlin+post`` a Python user function with the Iwan *virgin backbone* only (no
                   history, nothing to commit) plus an empty post-step function: a nonlinear
                   law, so generalized-alpha needs two Newton iterations (three calls) per
                   step as with the joint; the floor of any Python force law with a
                   once-per-step post-step function in this solver
* ``symbolic-nonlin+set`` the Iwan virgin backbone as an Exudyn *symbolic* law (no history)
                   plus a Python post-step function that writes one named symbolic variable
                   per step: the floor of the symbolic connector's design (three symbolic
                   force evaluations, one Python post-step call, one ``SetValue``)
* ``conn-linear``  :func:`add_iwan_connector` with a trivial linear element: the cost of
                   the connector machinery alone (trial-only force function, post-step
                   dispatcher, commit, records)
* ``conn-iwan``    :func:`add_iwan_connector` with :class:`IwanJoint`: the default route, the
                   exact symbolic law (records on / ``-norecord`` off)
* ``conn-iwan-python`` the same with ``law="python"`` (the Python force function)
* ``conn-discrete`` :func:`add_iwan_connector` with :class:`DiscreteIwan`, 100 sliders

With ``--compare-with DIR`` the ``conn-*`` variants are also run with the package found in
``DIR/iwan_element`` (e.g. an older revision: ``git archive <rev> iwan_element | tar -x -C
DIR``), interleaved with the current one, rows marked ``@base``.

Wall time is the best of ``--repeat`` runs of ``mbs.SolveDynamic`` only, the variants
interleaved in each round (the machine is shared: compare ratios within one run). Force
evaluations per step come from a separate counting run (not timed).

A second table (``--contacts N``, default 50; 0 skips it): a chain of N unit masses, each
joined to the previous one (the first to ground) along one axis, initial velocities
3 m/s * k/N, with Exudyn's built-in linear springs (``builtin``), with N stateless symbolic
backbone springs (``symbolic-backbone``: the floor of any symbolic nonlinear law, two Newton
iterations per step as for the joints), with
:func:`add_iwan_interface` (``interface``: N symbolic laws, one vectorised commit), with N
symbolic connectors (``connectors-symbolic``) and with N Python-law connectors
(``connectors-python``). The interface's trajectory is compared with the Python-law run.

Run: ``python benchmarks/bench_connector.py [--steps 100000] [--repeat 5] [--contacts 50]
[--contact-steps 20000] [--compare-with DIR]``
"""

from __future__ import annotations

import argparse
import importlib.util
import math
import sys
import time
from pathlib import Path

import exudyn as exu
import numpy as np
from exudyn.advancedUtilities import CreateSymbolicUserFunction
from exudyn.itemInterface import (
    CoordinateSpringDamper,
    MarkerNodeCoordinate,
    Mass1D,
    Node1D,
    NodePointGround,
    ObjectConnectorCoordinateSpringDamper,
)

import iwan_element
import iwan_element.exudyn
from iwan_element import IwanParameters

P = IwanParameters(Fs=1000.0, KT=1e6, chi=-0.5, beta=0.2)
H = 1e-5
V0 = 3.0


class LinearElement:
    """A spring KT following the element protocol, with nothing to compute: the floor."""

    def __init__(self, k):
        self.k = k
        self.displacement = self.force = self.work = self.dissipated_energy = 0.0
        self._u = 0.0

    def trial(self, u, v=0.0):
        self._u = u
        return self.k * u, self.k

    def commit(self):
        self.displacement = self._u
        self.force = self.k * self._u
        self.work = 0.5 * self.k * self._u * self._u

    stored_energy = property(lambda self: self.work)

    def revert(self):
        pass

    def reset(self):
        self.__init__(self.k)


class Counting:
    """Wraps an element and counts its trial calls (for the untimed counting run)."""

    def __init__(self, element, counter):
        self.element = element
        self.counter = counter

    def trial(self, u, v=0.0):
        self.counter[0] += 1
        return self.element.trial(u, v)

    def commit(self):
        self.element.commit()

    def revert(self):
        self.element.revert()

    def reset(self):
        self.element.reset()

    work = property(lambda self: self.element.work)
    stored_energy = property(lambda self: self.element.stored_energy)
    dissipated_energy = property(lambda self: self.element.dissipated_energy)
    displacement = property(lambda self: self.element.displacement)
    force = property(lambda self: self.element.force)


def load_package(directory):
    """Import ``directory/iwan_element`` under the name ``iwan_element_base``."""
    path = Path(directory).resolve() / "iwan_element"
    spec = importlib.util.spec_from_file_location(
        "iwan_element_base", path / "__init__.py", submodule_search_locations=[str(path)]
    )
    module = importlib.util.module_from_spec(spec)
    sys.modules["iwan_element_base"] = module
    spec.loader.exec_module(module)
    importlib.import_module("iwan_element_base.exudyn")
    return module


PACKAGES = {"": iwan_element}


def backbone_law():
    """Python force law: the virgin backbone only (nonlinear, no history)."""
    KT, Fs, pm = P.KT, P.Fs, P.phi_max
    e1 = P.chi + 1.0
    a = P.R / ((P.chi + 1.0) * (P.chi + 2.0))
    copysign = math.copysign

    def backbone(mbs_, t, itemNumber, deltaL, deltaL_t, stiffness, damping, offset):
        x = abs(deltaL)
        return copysign(x * (KT - a * x**e1) if x < pm else Fs, deltaL)

    return backbone


_KEEP = []


def symbolic_backbone_with_variable(mbs):
    """The virgin backbone as an Exudyn symbolic law, and a variable set once per step."""
    esym = exu.symbolic
    KT, Fs, pm = P.KT, P.Fs, P.phi_max
    e1 = P.chi + 1.0
    a = P.R / ((P.chi + 1.0) * (P.chi + 2.0))
    var = esym.Real(f"bench_uc_{id(mbs)}", 0.0)

    def law(mbs_, t, itemNumber, deltaL, deltaL_t, stiffness, damping, offset):
        x = esym.abs(deltaL)
        return esym.sign(deltaL) * esym.IfThenElse(
            x < pm, x * (KT - a * esym.pow(x, e1)), esym.Real(Fs)
        )

    fn = CreateSymbolicUserFunction(
        mbs, law, "springForceUserFunction", itemTypeName="ObjectConnectorCoordinateSpringDamper"
    )
    return fn, var


def build(variant, counter=None):
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddNode(NodePointGround())
    node = mbs.AddNode(Node1D(referenceCoordinates=[0.0], initialVelocities=[V0]))
    mbs.AddObject(Mass1D(mass=1.0, nodeNumber=node))
    m0 = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0))
    m1 = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=node, coordinate=0))
    if variant == "builtin":
        mbs.AddObject(CoordinateSpringDamper(markerNumbers=[m0, m1], stiffness=P.KT))
    elif variant == "symbolic-nonlin+set":
        fn, var = symbolic_backbone_with_variable(mbs)
        mbs.AddObject(
            ObjectConnectorCoordinateSpringDamper(
                markerNumbers=[m0, m1], stiffness=0.0, damping=0.0, springForceUserFunction=fn
            )
        )
        set_value = var.SetValue
        item = None

        def post(mbs_, t):
            set_value(item(0))
            return True

        mbs.SetPostStepUserFunction(post)
        mbs.Assemble()
        item = mbs.systemData.GetODE2Coordinates(copy=False).item
        _KEEP[:] = [fn, var]  # the expression must outlive the run
        return SC, mbs
    elif variant.startswith("python-"):

        def linear(mbs_, t, itemNumber, deltaL, deltaL_t, stiffness, damping, offset):
            return stiffness * deltaL

        law = backbone_law() if variant.startswith("python-nonlin") else linear
        mbs.AddObject(
            CoordinateSpringDamper(
                markerNumbers=[m0, m1], stiffness=P.KT, springForceUserFunction=law
            )
        )
        if variant.endswith("+post"):
            mbs.SetPostStepUserFunction(lambda mbs_, t: True)
    else:
        name, _, tag = variant.partition("@")
        pkg = PACKAGES[tag]
        params = pkg.IwanParameters(Fs=P.Fs, KT=P.KT, chi=P.chi, beta=P.beta)
        element = {
            "conn-linear": lambda: LinearElement(P.KT),
            "conn-iwan": lambda: pkg.IwanJoint(params),
            "conn-iwan-norecord": lambda: pkg.IwanJoint(params),
            "conn-iwan-python": lambda: pkg.IwanJoint(params),
            "conn-discrete": lambda: pkg.DiscreteIwan(params, 100),
        }[name]()
        if counter is not None:
            element = Counting(element, counter)
        kw = {}
        if not tag:  # the law keyword is new
            kw["law"] = "python" if name == "conn-iwan-python" else "auto"
        pkg.exudyn.add_iwan_connector(
            mbs, [m0, m1], element, record=(name != "conn-iwan-norecord"), **kw
        )
    mbs.Assemble()
    return SC, mbs


def settings(steps):
    sim = exu.SimulationSettings()
    sim.timeIntegration.numberOfSteps = steps
    sim.timeIntegration.endTime = steps * H
    sim.timeIntegration.verboseMode = 0
    sim.solution.file.write = False
    sim.parallel.numberOfThreads = 1
    return sim


def timed_run(variant, steps):
    SC, mbs = build(variant)
    sim = settings(steps)
    t0 = time.perf_counter()
    mbs.SolveDynamic(sim)
    wall = time.perf_counter() - t0
    return wall, mbs.sys["dynamicSolver"].it.newtonStepsCount / steps


def count_trials(variant, steps):
    if not variant.startswith("conn"):
        return float("nan")
    counter = [0]
    n = min(steps, 20000)
    SC, mbs = build(variant, counter)
    mbs.SolveDynamic(settings(n))
    return counter[0] / n


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=100_000, help="1-mass table (0: skip it)")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument(
        "--compare-with",
        metavar="DIR",
        help="also run the conn-* variants with DIR/iwan_element (rows '@base')",
    )
    ap.add_argument("--no-discrete", action="store_true", help="skip the slow conn-discrete")
    ap.add_argument(
        "--contacts", type=int, default=50, help="contacts of the chain table (0: skip)"
    )
    ap.add_argument("--contact-steps", type=int, default=20_000)
    args = ap.parse_args(argv)
    conn = ["conn-linear", "conn-iwan", "conn-iwan-norecord", "conn-iwan-python"]
    if not args.no_discrete:
        conn.append("conn-discrete")
    if args.compare_with:
        PACKAGES["base"] = load_package(args.compare_with)
        conn = [c for v in conn for c in (v + "@base", v)]
    if args.steps <= 0:  # only the contact table
        contact_table(args.contacts, args.contact_steps, args.repeat)
        return
    variants = [
        "builtin",
        "python-lin",
        "python-lin+post",
        "python-nonlin+post",
        "symbolic-nonlin+set",
    ] + conn
    best = dict.fromkeys(variants, (math.inf, math.nan))
    for _ in range(args.repeat):  # interleaved rounds: load changes hit all variants
        for v in variants:
            if v.startswith("conn-discrete") and _ > 1:
                continue
            wall, newton = timed_run(v, args.steps)
            if wall < best[v][0]:
                best[v] = (wall, newton)
    base = best["builtin"][0]
    print(
        f"one mass, {args.steps} steps, generalized-alpha (default settings), h = {H:g} s, "
        f"exudyn {exu.__version__}, best of {args.repeat} interleaved rounds"
    )
    print(
        f"{'variant':<24} {'wall [s]':>9} {'ratio':>7} {'us/step':>8} {'Newton it/step':>15} "
        f"{'trials/step':>12}"
    )
    for v in variants:
        t, newton = best[v]
        evals = count_trials(v, args.steps)
        ev = "-" if evals != evals else f"{evals:.2f}"
        print(
            f"{v:<24} {t:9.3f} {t / base:7.1f} {1e6 * t / args.steps:8.2f} {newton:15.2f} {ev:>12}"
        )
    if args.contacts > 0:
        contact_table(args.contacts, args.contact_steps, args.repeat)


def build_chain(variant, n):
    """N unit masses in a chain along one axis, joined by springs or Iwan joints."""
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddNode(NodePointGround())
    markers = [mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0))]
    for k in range(n):
        node = mbs.AddNode(Node1D(referenceCoordinates=[0.0], initialVelocities=[V0 * (k + 1) / n]))
        mbs.AddObject(Mass1D(mass=1.0, nodeNumber=node))
        markers.append(mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=node, coordinate=0)))
    pairs = [(markers[k], markers[k + 1]) for k in range(n)]
    handle = None
    if variant == "builtin":
        for m0, m1 in pairs:
            mbs.AddObject(CoordinateSpringDamper(markerNumbers=[m0, m1], stiffness=P.KT))
    elif variant == "symbolic-backbone":
        handle = [symbolic_backbone(mbs, m0, m1) for m0, m1 in pairs]  # keep them alive
    elif variant.startswith("interface"):
        pkg = PACKAGES[variant.partition("@")[2]]
        params = pkg.IwanParameters(Fs=P.Fs, KT=P.KT, chi=P.chi, beta=P.beta)
        handle = pkg.exudyn.add_iwan_interface(mbs, pairs, [params] * n)
    else:
        law = "python" if variant == "connectors-python" else "symbolic"
        handle = [
            iwan_element.exudyn.add_iwan_connector(
                mbs, list(pr), iwan_element.IwanJoint(P), law=law
            )
            for pr in pairs
        ]
    mbs.Assemble()
    return SC, mbs, handle


def symbolic_backbone(mbs, m0, m1):
    """A spring whose force is the Iwan virgin backbone as an Exudyn symbolic expression: a
    stateless nonlinear symbolic law (no post-step), the floor of any symbolic Iwan law.
    """
    from exudyn.advancedUtilities import CreateSymbolicUserFunction

    esym = exu.symbolic
    a, e1, pm = P.R / ((P.chi + 1.0) * (P.chi + 2.0)), P.chi + 1.0, P.phi_max

    def law(mbs_, t, itemNumber, deltaL, deltaL_t, stiffness, damping, offset):
        x = esym.abs(deltaL)
        return esym.sign(deltaL) * esym.IfThenElse(
            x < pm, x * (P.KT - a * esym.pow(x, e1)), esym.Real(P.Fs)
        )

    fn = CreateSymbolicUserFunction(
        mbs, law, "springForceUserFunction", itemTypeName="ObjectConnectorCoordinateSpringDamper"
    )
    mbs.AddObject(
        CoordinateSpringDamper(markerNumbers=[m0, m1], stiffness=0.0, springForceUserFunction=fn)
    )
    return fn


def contact_table(n, steps, repeat):
    """The chain table: wall and CPU time (best of the interleaved rounds), Newton iterations
    per step, and the trajectory against the Python-law connectors.
    """
    variants = [
        "builtin",
        "symbolic-backbone",
        "interface",
        "connectors-symbolic",
        "connectors-python",
    ]
    if "base" in PACKAGES:
        variants.insert(2, "interface@base")
    best = dict.fromkeys(variants, (math.inf, math.inf, math.nan))
    slips = {}
    for _ in range(repeat):
        for v in variants:
            SC, mbs, handle = build_chain(v, n)
            t0, c0 = time.perf_counter(), time.process_time()
            mbs.SolveDynamic(settings(steps))
            wall, cpu = time.perf_counter() - t0, time.process_time() - c0
            newton = mbs.sys["dynamicSolver"].it.newtonStepsCount / steps
            w, c, _ = best[v]
            best[v] = (min(w, wall), min(c, cpu), newton)
            if v.startswith("interface"):
                slips[v] = handle.slip_history
            elif v.startswith("connectors"):
                slips[v] = np.stack([c.slip_history for c in handle], axis=1)
    base_w, base_c, _ = best["builtin"]
    amp = float(np.max(np.abs(slips["connectors-python"])))
    print(
        f"\nchain of {n} masses and {n} contacts, {steps} steps, h = {H:g} s, best of {repeat} "
        "interleaved rounds (CPU: process time, less sensitive to other load)"
    )
    print(
        f"{'variant':<24} {'wall [s]':>9} {'ratio':>7} {'us/step':>8} {'CPU ratio':>10} "
        f"{'Newton it/step':>15} {'max |slip - python| / amp':>26}"
    )
    for v in variants:
        w, c, newton = best[v]
        dev = (
            "-"
            if v not in slips
            else f"{np.max(np.abs(slips[v] - slips['connectors-python'])) / amp:.1e}"
        )
        print(
            f"{v:<24} {w:9.3f} {w / base_w:7.2f} {1e6 * w / steps:8.2f} {c / base_c:10.2f} "
            f"{newton:15.2f} {dev:>26}"
        )


if __name__ == "__main__":
    main()
