"""Accepted slips read from Exudyn's coordinates after each step (never inside a force law),
and their per-step records.

:mod:`.slip_map` (slips of many marker pairs from a view of the coordinates),
:mod:`.surface_slips` (contact points on ANCF Cable2D surfaces, vectorised),
:mod:`.slip_records` (the interface's per-step slips; forces and energies replayed).
"""

from .slip_map import SlipMap
from .slip_records import SlipRecords
from .surface_slips import SurfaceSlips

__all__ = ["SlipMap", "SlipRecords", "SurfaceSlips"]
