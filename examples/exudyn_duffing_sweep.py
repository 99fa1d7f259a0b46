"""A mass on a coordinate spring-damper swept through resonance; the spring swapped for an
Iwan joint in one call.

The model follows the pattern of Exudyn's spring-damper user-function test (a 1.6 kg mass
point on a ``CoordinateSpringDamper`` whose Python user function is a hardening spring
``0.1 k u + k u^3`` plus the damper ``d v``, driven by an 80 N load swept linearly from 0 to
the linear resonance over 50 s in 5000 steps), written here from scratch. The swap: the
spring becomes ``create_iwan_connector`` on the same two coordinate markers, its damper the
joint's dashpot in parallel (``damping=d``). Run::

    python examples/exudyn_duffing_sweep.py          # the script's own 5000 steps
    python examples/exudyn_duffing_sweep.py --steps 40000
"""

from __future__ import annotations

import argparse
import math
import time
from types import SimpleNamespace

import exudyn as exu
import numpy as np
from exudyn.itemInterface import (
    CoordinateSpringDamper,
    LoadCoordinate,
    MarkerNodeCoordinate,
    MassPoint,
    NodePoint,
    NodePointGround,
)

from iwan_element import IwanParameters
from iwan_element.exudyn import create_iwan_connector, record_energy

MASS, K, D, LOAD = 1.6, 4000.0, 4.0, 80.0  # kg, N/m, N s/m, N
T_END = 50.0  # s
F1 = math.sqrt(K / MASS) / (2.0 * math.pi)  # Hz, end of the sweep (linear resonance)
JOINT = IwanParameters(Fs=120.0, KT=K, chi=-0.5, beta=0.5)  # N, N/m, -, -


def sweep_load(mbs, t, load):
    """The load [N]: ``load sin(2 pi (f0 + (f1 - f0) t / (2 T)) t)`` from 0 to ``F1``."""
    return load * math.sin(2.0 * math.pi * (0.5 * F1 * t / T_END) * t)


def hardening_spring(mbs, t, itemNumber, u, v, k, d, offset):
    """The script's own user-function spring: ``0.1 k u + k u^3 + d v`` [N]."""
    return 0.1 * k * u + k * u**3 + d * v


def build(
    joint: str = "iwan",
    *,
    steps: int = 5000,
    law: str = "auto",
    energy: bool = False,
    t_end: float = T_END,
):
    """The model. ``joint="spring"``: the script's user-function spring; ``"iwan"``: the
    Iwan joint swapped in. Returns a namespace with ``SC, mbs, sim, connector, recorder``.
    """
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    node = mbs.AddNode(NodePoint(referenceCoordinates=[0.5, 0.0, 0.0]))
    mbs.AddObject(MassPoint(mass=MASS, nodeNumber=node))
    ground = mbs.AddMarker(
        MarkerNodeCoordinate(nodeNumber=mbs.AddNode(NodePointGround()), coordinate=0)
    )
    marker = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=node, coordinate=0))
    connector = None
    if joint == "spring":
        mbs.AddObject(
            CoordinateSpringDamper(
                markerNumbers=[ground, marker],
                stiffness=K,
                damping=D,
                springForceUserFunction=hardening_spring,
            )
        )
    else:  # the swap: one call
        connector = create_iwan_connector(
            mbs, bodyNumbers=[ground, marker], parameters=JOINT, damping=D, law=law
        )
    mbs.AddLoad(LoadCoordinate(markerNumber=marker, load=LOAD, loadUserFunction=sweep_load))
    recorder = record_energy(mbs, connector) if energy else None
    mbs.Assemble()
    sim = exu.SimulationSettings()
    ti = sim.timeIntegration
    ti.numberOfSteps, ti.endTime = int(steps), float(t_end)
    ti.generalizedAlpha.spectralRadius = 1.0
    ti.verboseMode = 0
    sim.solution.file.write = False
    return SimpleNamespace(
        SC=SC, mbs=mbs, sim=sim, connector=connector, recorder=recorder, node=node
    )


def run(model) -> float:
    """Solve; returns the wall time [s]."""
    t0 = time.perf_counter()
    model.mbs.SolveDynamic(model.sim)
    return time.perf_counter() - t0


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=5000, help="time steps over the 50 s sweep")
    args = ap.parse_args(argv)
    model = build("iwan", steps=args.steps, energy=True)
    wall = run(model)
    conn = model.connector
    u = conn.slip_history[:, 0]
    print(
        f"{args.steps} steps ({wall:.2f} s): peak slip {np.max(np.abs(u)) * 1e3:.2f} mm "
        f"(phi_max {JOINT.phi_max * 1e3:.2f} mm), the joint and its dashpot dissipated "
        f"{conn.dissipated_energy_history[-1]:.3f} J"
    )
    print(model.recorder.balance().report())


if __name__ == "__main__":
    main()
