"""Per-step records of the symbolic interface: slips only, forces and energies replayed.

The interface stores one row ``(t, slip[n_points])`` per accepted step (preallocated arrays
that grow geometrically; nothing with ``on=False``). Forces and energies are not stored per
step: they are recomputed from the slips when read, by committing the same rows to a fresh
:class:`~iwan_element.core.joint_bank.IwanJointBank` (an exact replay of the interface's own
commits). The replay is incremental: rows already replayed are not replayed again.
"""

from __future__ import annotations

import numpy as np

from ...core.joint_bank import IwanJointBank

__all__ = ["SlipRecords"]

_START = 1024


class SlipRecords:
    """Rows ``(t, slip[n_points])`` and the replayed ``force``, ``work``, ``diss``."""

    _replay: IwanJointBank | None  # the bank the rows are replayed on (None: not yet)

    def __init__(self, n_points: int, on: bool):
        self.on = on
        self.n_points = n_points
        self.clear()

    def clear(self) -> None:
        """Drop every row and the replay; return None."""
        cap = _START if self.on else 0
        self.n = 0
        self.t = np.empty(cap)
        self.slip = np.empty((cap, self.n_points))
        self._replay = None
        self._done = 0
        self._force = np.empty((0, self.n_points))
        self._work = np.empty(0)
        self._diss = np.empty(0)

    def append(self, t, u) -> None:
        """Append the row ``(t [s], u [m])``, growing the buffers; return None."""
        k = self.n
        if k == len(self.t):
            cap = 2 * max(k, _START // 2)
            t_new, s_new = np.empty(cap), np.empty((cap, self.n_points))
            t_new[:k], s_new[:k] = self.t[:k], self.slip[:k]
            self.t, self.slip = t_new, s_new
        self.t[k] = t
        self.slip[k] = u
        self.n = k + 1

    def _advance(self, bank) -> None:
        """Replay the rows not replayed yet."""
        n = self.n
        if self._replay is None:
            self._replay = IwanJointBank(bank.params, reversal_tol=bank._rtol)
        if len(self._work) < n:
            cap = max(n, 2 * len(self._work), _START)
            F, W, D = np.empty((cap, self.n_points)), np.empty(cap), np.empty(cap)
            k = self._done
            F[:k], W[:k], D[:k] = self._force[:k], self._work[:k], self._diss[:k]
            self._force, self._work, self._diss = F, W, D
        replay = self._replay
        for k in range(self._done, n):
            replay.commit(self.slip[k])
            self._force[k] = replay.force
            self._work[k] = replay.work.sum()
            self._diss[k] = replay.dissipated_energy.sum()
        self._done = n

    def table(self, bank) -> dict:
        """Copies of ``time``, ``slip``, ``force``, ``work`` and ``diss`` (n rows)."""
        self._advance(bank)
        n = self.n
        return {
            "time": self.t[:n].copy(),
            "slip": self.slip[:n].copy(),
            "force": self._force[:n].copy(),
            "work": self._work[:n].copy(),
            "diss": self._diss[:n].copy(),
        }
