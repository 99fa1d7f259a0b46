"""The force laws Exudyn evaluates for the Iwan connectors and interfaces.

:mod:`.symbolic_law` (the exact Iwan law as an Exudyn symbolic expression, no Python call per
evaluation), :mod:`.symbolic_connector` (its per-step work for one connector: the accepted
slip written to the law, the joint committed lazily), :mod:`.symbolic_records` (its records,
replayed when read), :mod:`.python_law` (the reference route: closures calling
``joint.trial``), :mod:`.interface_springs` (linear springs carried by the interface's own
objects).
"""

from .interface_springs import add_builtin_springs, check_stiffness, linear_energy
from .python_law import (
    coordinate_force_function,
    position_force_function,
    rotating_axis_force_function,
)
from .symbolic_law import (
    VIRGIN,
    SymbolicIwanState,
    branch_of,
    cartesian_law,
    committed_slip_matrix,
    coordinate_law,
    make_probe,
    rigid_law,
)

__all__ = [
    "add_builtin_springs",
    "check_stiffness",
    "linear_energy",
    "coordinate_force_function",
    "position_force_function",
    "rotating_axis_force_function",
    "VIRGIN",
    "SymbolicIwanState",
    "branch_of",
    "cartesian_law",
    "committed_slip_matrix",
    "coordinate_law",
    "make_probe",
    "rigid_law",
]
