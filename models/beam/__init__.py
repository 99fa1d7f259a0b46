"""The 1-D lap-jointed beam: planar Timoshenko (or Euler-Bernoulli) finite elements with
their read-out rows, and the 1-D specimen's linear system built from them.
"""

from .assembly import beam_axis_rows, beam_linear_system
from .elements import (
    NODE_DOFS,
    BeamMesh,
    beam_matrices,
    beam_mesh,
    element_matrices,
    grip_coordinates,
    interface_rows,
    point_rows,
)

__all__ = [
    "BeamMesh",
    "beam_mesh",
    "element_matrices",
    "beam_matrices",
    "point_rows",
    "interface_rows",
    "grip_coordinates",
    "NODE_DOFS",
    "beam_linear_system",
    "beam_axis_rows",
]
