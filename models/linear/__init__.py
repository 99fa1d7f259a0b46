"""The linear system every analysis reads (mass, stiffness and the rows of the contact
slips and gaps, sensor, excitation), the type the 1-D beams and the solid bodies both give,
and the test setup built into it the same way for both.
"""

from .system import LinearSystem, attach_setup

__all__ = ["LinearSystem", "attach_setup"]
