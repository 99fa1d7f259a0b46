"""A reduced flexible rotor on two bearings; one bearing direction swapped for an Iwan joint.

The model follows the pattern of Exudyn's reduced-order rotor test (a floating-frame
reduced-order body, ``ObjectFFRFreducedOrder``, spinning at 50 Hz on Cartesian
spring-damper bearings at its end faces, an unbalance mass driving the whirl), built here
from scratch on a finite-element mesh of our own: a space truss of bars (a square prism,
braced in every face and section), assembled below with numpy (lumped masses, axial bar
stiffness), reduced to 8 free-free modes by Exudyn's ``FEMinterface``.

The swap is one call: the right bearing's ``CartesianSpringDamper`` (stiffness [0, k, k])
becomes ``create_iwan_connector`` with the Iwan law along y and the spring on z. The joint
rides on the spinning flexible body, whose marker position is not affine in the
coordinates; the default route reads the slip exactly every step. Run::

    python examples/exudyn_rotor_bearing.py            # 0.05 s, default route and law="python"
"""

from __future__ import annotations

import argparse
import time
from types import SimpleNamespace

import exudyn as exu
import numpy as np
import scipy.sparse as sp
from exudyn.FEM import FEMinterface, ObjectFFRFreducedOrderInterface
from exudyn.itemInterface import (
    MarkerBodyPosition,
    MarkerSuperElementPosition,
    ObjectConnectorCartesianSpringDamper,
    ObjectGround,
    SensorMarker,
)

from iwan_element import IwanParameters
from iwan_element.exudyn import create_iwan_connector, record_energy

LENGTH, HALF_WIDTH, BAYS = 0.5, 0.02, 10  # m, m, -
BAR_EA, MASS = 4.0e6, 6.28  # N, kg
UNBALANCE = 0.1  # kg at a mid-span corner node
SPIN = 50.0  # Hz
K_BEARING = 2.0e7  # N/m
D_BEARING = 0.01 * K_BEARING  # N s/m (as Exudyn's test: 1 % of k)
JOINT = IwanParameters(Fs=30.0, KT=K_BEARING, chi=-0.5, beta=0.5)  # N, N/m, -, -


def truss_rotor() -> FEMinterface:
    """The rotor's finite-element model: ``BAYS + 1`` square sections of four nodes along x,
    joined by longitudinal and face-diagonal bars, each section braced by its edges and both
    diagonals (a stable space truss: exactly six rigid-body modes), bar stiffness ``EA / l``,
    the mass lumped equally at the nodes, plus the unbalance at a mid-span corner.
    """
    r = HALF_WIDTH
    corners = np.array([[0.0, r, r], [0.0, -r, r], [0.0, -r, -r], [0.0, r, -r]])
    pos = np.concatenate([corners + [i * LENGTH / BAYS, 0.0, 0.0] for i in range(BAYS + 1)])
    bars = []
    for i in range(BAYS + 1):
        b = 4 * i
        bars += [(b + k, b + (k + 1) % 4) for k in range(4)] + [(b, b + 2), (b + 1, b + 3)]
        if i < BAYS:
            bars += [(b + k, b + 4 + k) for k in range(4)]
            bars += [(b + k, b + 4 + (k + 1) % 4) for k in range(4)]
    rows, cols, vals = [], [], []
    for a, b in bars:
        e = pos[b] - pos[a]
        length = np.linalg.norm(e)
        ke = BAR_EA / length * np.outer(e, e) / length**2
        for i, j, s in ((a, a, 1.0), (b, b, 1.0), (a, b, -1.0), (b, a, -1.0)):
            ii, jj = np.meshgrid(3 * i + np.arange(3), 3 * j + np.arange(3), indexing="ij")
            rows += ii.ravel().tolist()
            cols += jj.ravel().tolist()
            vals += (s * ke).ravel().tolist()
    n = 3 * len(pos)
    fem = FEMinterface()
    fem.nodes = {"Position": pos}
    fem.stiffnessMatrix = sp.csr_matrix((vals, (rows, cols)), shape=(n, n))
    fem.massMatrix = sp.diags(np.full(n, MASS / len(pos))).tocsr()
    fem.AddNodeMass(4 * (BAYS // 2), UNBALANCE)
    fem.ComputeEigenmodes(8, excludeRigidBodyModes=6, useSparseSolver=False)
    return fem


def _face_marker(mbs, body, fem, x):
    nodes = fem.GetNodesInPlane([x, 0.0, 0.0], [1.0, 0.0, 0.0])
    return mbs.AddMarker(
        MarkerSuperElementPosition(
            bodyNumber=body, meshNodeNumbers=nodes, weightingFactors=[1.0 / len(nodes)] * len(nodes)
        )
    )


def build(
    joint: str = "iwan",
    *,
    law: str = "auto",
    t_end: float = 0.05,
    h: float = 1e-4,
    rho: float = 0.5,
    energy: bool = False,
    fem=None,
):
    """The rotor model, solved by :func:`run`. ``joint="spring"``: Exudyn's bearing as it is;
    ``"iwan"``: the right bearing's y direction an Iwan joint (``law`` as in
    ``add_iwan_connector``). Returns a namespace with ``SC, mbs, sim, connector, recorder,
    sensor, fem``.
    """
    fem = truss_rotor() if fem is None else fem
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    rotor = ObjectFFRFreducedOrderInterface(fem).AddObjectFFRFreducedOrder(
        mbs,
        positionRef=[0.0, 0.0, 0.0],
        initialVelocity=[0.0, 0.0, 0.0],
        initialAngularVelocity=[2.0 * np.pi * SPIN, 0.0, 0.0],
    )
    body = rotor["oFFRFreducedOrder"]
    m_left, m_right = _face_marker(mbs, body, fem, 0.0), _face_marker(mbs, body, fem, LENGTH)
    ground = mbs.AddObject(ObjectGround())
    g_left = mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground, localPosition=[0.0, 0.0, 0.0]))
    g_right = mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground, localPosition=[LENGTH, 0.0, 0.0]))
    k, d = K_BEARING, D_BEARING
    mbs.AddObject(
        ObjectConnectorCartesianSpringDamper(
            markerNumbers=[m_left, g_left], stiffness=[k, k, k], damping=[d, d, d]
        )
    )
    connector = None
    if joint == "spring":
        mbs.AddObject(
            ObjectConnectorCartesianSpringDamper(
                markerNumbers=[m_right, g_right], stiffness=[0.0, k, k], damping=[d, d, d]
            )
        )
    else:  # the swap: one call
        connector = create_iwan_connector(
            mbs,
            bodyNumbers=[m_right, g_right],
            axis=[0, 1, 0],
            parameters=JOINT,
            stiffness=[0.0, 0.0, k],
            damping=[d, d, d],
            law=law,
        )
    sensor = mbs.AddSensor(
        SensorMarker(
            markerNumber=m_right,
            storeInternal=True,
            outputVariableType=exu.OutputVariableType.Position,
        )
    )
    recorder = record_energy(mbs, connector) if energy else None
    mbs.Assemble()
    sim = exu.SimulationSettings()
    ti = sim.timeIntegration
    ti.numberOfSteps, ti.endTime = int(round(t_end / h)), t_end
    ti.newton.useModifiedNewton = True
    ti.generalizedAlpha.spectralRadius = rho
    ti.verboseMode = 0
    sim.solution.file.write = False
    sim.solution.sensors.writePeriod = h
    return SimpleNamespace(
        SC=SC,
        mbs=mbs,
        sim=sim,
        connector=connector,
        recorder=recorder,
        sensor=sensor,
        fem=fem,
        right=m_right,
    )


def run(model) -> float:
    """Solve; returns the wall time [s]."""
    t0 = time.perf_counter()
    model.mbs.SolveDynamic(model.sim)
    return time.perf_counter() - t0


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--t-end", type=float, default=0.05, help="simulated time [s]")
    args = ap.parse_args(argv)
    fem = truss_rotor()
    print("free-free frequencies [Hz]:", np.round(fem.GetEigenFrequenciesHz()[6:10], 1))
    out = {}
    for law in ("auto", "python"):
        model = build("iwan", law=law, t_end=args.t_end, fem=fem)
        wall = run(model)
        conn = model.connector
        out[law] = conn.dissipated_energy_history[-1]
        print(
            f"law={law:6s} ({conn.connectors[0].route}): joint dissipated {out[law]:.6e} J, "
            f"peak slip {np.max(np.abs(conn.slip_history)) * 1e6:.3f} um, {wall:.2f} s"
        )
    rel = abs(out["auto"] - out["python"]) / out["python"]
    print(f"default route against the exact read-out (law='python'): {rel:.2e} relative")


if __name__ == "__main__":
    main()
