"""Per-step records of an interface, in preallocated arrays (or off)."""
from __future__ import annotations

import numpy as np

__all__: list[str] = []

_START = 1024


class InterfaceRecords:
    """Rows ``(t, slip[n_points], force[n_points], work_total, dissipated_total)``.

    Storage grows geometrically (amortised O(1) per row, no per-row allocation); with
    ``on=False`` nothing is stored and :meth:`append` is never called by the interface.
    """

    def __init__(self, n_points: int, on: bool):
        self.on = on
        self.n_points = n_points
        self.clear()

    def clear(self) -> None:
        cap = _START if self.on else 0
        self.n = 0
        self.t = np.empty(cap)
        self.slip = np.empty((cap, self.n_points))
        self.force = np.empty((cap, self.n_points))
        self.work = np.empty(cap)
        self.diss = np.empty(cap)

    def _grow(self) -> None:
        cap = 2 * max(len(self.t), _START // 2)
        for name in ("t", "slip", "force", "work", "diss"):
            old = getattr(self, name)
            new = np.empty((cap,) + old.shape[1:])
            new[:self.n] = old[:self.n]
            setattr(self, name, new)

    def append(self, t, slip, force, work, diss) -> None:
        k = self.n
        if k == len(self.t):
            self._grow()
        self.t[k] = t
        self.slip[k] = slip
        self.force[k] = force
        self.work[k] = work
        self.diss[k] = diss
        self.n = k + 1
