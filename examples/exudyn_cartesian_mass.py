"""A mass point on a three-dimensional spring-damper; its x direction swapped for an Iwan
joint in one call.

The model follows the pattern of Exudyn's Cartesian spring-damper example (a 1.6 kg mass
point at ``[L, 0, 0]`` on ``mbs.CreateCartesianSpringDamper`` with stiffness ``[k, k, k]``,
damping ``[d, 0, 0]`` and ``offset=[L, 0, 0]``, a constant 80 N force along x, released from
``u0 = -0.08 m`` with ``v0 = 1 m/s``), written here from scratch; a velocity across the axis
and optional gravity make the remaining axes work too. The swap: the spring-damper becomes
``create_iwan_connector`` with the Iwan law along x and the same call's springs on y and z
(``stiffness=[0, k, k]``), its damper and offset as they were. Run::

    python examples/exudyn_cartesian_mass.py                 # 1 s in 100 000 steps
    python examples/exudyn_cartesian_mass.py --gravity       # with gravity along -y
"""

from __future__ import annotations

import argparse
import time
from types import SimpleNamespace

import exudyn as exu
import numpy as np

from iwan_element import IwanParameters
from iwan_element.exudyn import create_iwan_connector, record_energy

L, MASS, K = 0.5, 1.6, 4000.0  # m, kg, N/m
D = 0.05 * 2.0 * np.sqrt(MASS * K)  # N s/m (5 % of critical)
FORCE, U0, V0 = 80.0, -0.08, 1.0  # N, m, m/s
JOINT = IwanParameters(Fs=120.0, KT=K, chi=-0.5, beta=0.5)  # N, N/m, -, -


def build(
    joint: str = "iwan",
    *,
    steps: int = 100_000,
    t_end: float = 1.0,
    law: str = "auto",
    energy: bool = False,
    gravity: bool = False,
):
    """The model. ``joint="spring"``: Exudyn's Cartesian spring-damper as it is; ``"iwan"``:
    the Iwan joint swapped in along x. Returns a namespace with ``SC, mbs, sim, connector,
    recorder, body``.
    """
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.CreateGround(referencePosition=[0.0, 0.0, 0.0])
    body = mbs.CreateMassPoint(
        referencePosition=[L, 0.0, 0.0],
        initialDisplacement=[U0, 0.0, 0.0],
        initialVelocity=[V0, 0.3, 0.0],
        mass=MASS,
        gravity=[0.0, -9.81, 0.0] if gravity else [0.0, 0.0, 0.0],
    )
    connector = None
    if joint == "spring":
        mbs.CreateCartesianSpringDamper(
            itemNumbers=[ground, body],
            stiffness=[K, K, K],
            damping=[D, 0.0, 0.0],
            offset=[L, 0.0, 0.0],
        )
    else:  # the swap: one call
        connector = create_iwan_connector(
            mbs,
            bodyNumbers=[ground, body],
            axis=[1, 0, 0],
            parameters=JOINT,
            stiffness=[0.0, K, K],
            damping=[D, 0.0, 0.0],
            offset=[L, 0.0, 0.0],
            law=law,
        )
    mbs.CreateForce(itemNumber=body, loadVector=[FORCE, 0.0, 0.0])
    recorder = record_energy(mbs, connector) if energy else None
    mbs.Assemble()
    sim = exu.SimulationSettings()
    ti = sim.timeIntegration
    ti.numberOfSteps, ti.endTime = int(steps), float(t_end)
    ti.newton.useModifiedNewton = True
    ti.generalizedAlpha.spectralRadius = 1.0
    ti.verboseMode = 0
    sim.solution.file.write = False
    return SimpleNamespace(
        SC=SC, mbs=mbs, sim=sim, connector=connector, recorder=recorder, body=body
    )


def run(model) -> float:
    """Solve; returns the wall time [s]."""
    t0 = time.perf_counter()
    model.mbs.SolveDynamic(model.sim)
    return time.perf_counter() - t0


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=100_000, help="time steps over 1 s")
    ap.add_argument("--gravity", action="store_true", help="gravity along -y")
    args = ap.parse_args(argv)
    model = build("iwan", steps=args.steps, energy=True, gravity=args.gravity)
    wall = run(model)
    conn = model.connector
    u = conn.slip_history[:, 0]
    p = model.mbs.GetObjectOutputBody(model.body, exu.OutputVariableType.Displacement)
    print(
        f"{args.steps} steps ({wall:.2f} s): slip from {u[0] * 1e3:.1f} to {u[-1] * 1e3:.2f} mm, "
        f"final displacement {np.round(np.asarray(p) * 1e3, 3)} mm, joint dissipated "
        f"{conn.dissipated_energy_history[-1]:.4f} J"
    )
    print(model.recorder.balance().report())


if __name__ == "__main__":
    main()
