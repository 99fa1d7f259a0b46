"""Quickstart: a 1 kg mass on a bolted joint (four-parameter Iwan model), driven harmonically."""

import math
import os

import exudyn as exu
from exudyn.itemInterface import (
    LoadCoordinate,
    MarkerNodeCoordinate,
    Mass1D,
    Node1D,
    NodePointGround,
)

from iwan_element import IwanParameters
from iwan_element.exudyn import add_iwan_connector

steps = int(os.environ.get("IWAN_QUICKSTART_STEPS", "20000"))  # h = 10 us
SC = exu.SystemContainer()
mbs = SC.AddSystem()
node = mbs.AddNode(Node1D(referenceCoordinates=[0.0]))
mbs.AddObject(Mass1D(mass=1.0, nodeNumber=node))
mGround = mbs.AddMarker(
    MarkerNodeCoordinate(nodeNumber=mbs.AddNode(NodePointGround()), coordinate=0)
)
mMass = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=node, coordinate=0))
mbs.AddLoad(
    LoadCoordinate(
        markerNumber=mMass,  # 400 N at 50 Hz
        loadUserFunction=lambda mbs, t, load: 400.0 * math.sin(2 * math.pi * 50.0 * t),
    )
)
params = IwanParameters(Fs=1000.0, KT=1e6, chi=-0.5, beta=0.2)  # N, N/m, -, -
joint = add_iwan_connector(mbs, [mGround, mMass], params)
mbs.Assemble()
sim = exu.SimulationSettings()
sim.timeIntegration.numberOfSteps, sim.timeIntegration.endTime = steps, steps * 1e-5
sim.timeIntegration.verboseMode, sim.solution.file.write = 0, False
mbs.SolveDynamic(sim)
print(
    f"peak slip {1e3 * abs(joint.slip_history).max():.4f} mm "
    f"(phi_max {1e3 * params.phi_max:.4f} mm), "
    f"dissipated {joint.dissipated_energy_history[-1]:.4f} J, "
    f"stored {joint.stored_energy_history[-1]:.4f} J"
)
