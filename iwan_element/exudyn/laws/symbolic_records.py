"""The records of a symbolic-route connector (:mod:`.symbolic_connector`): ``(t, u)`` per
accepted step (``(t, u, v)`` with a dashpot), replayed when read on a copy of the joint
taken where the records start (the same ``trial``/``commit`` sequence as a per-step commit,
so the same numbers), cached and extended incrementally.
"""

from __future__ import annotations

import copy

import numpy as np

__all__ = ["stride", "replay_records"]


def stride(conn) -> int:
    """Values recorded per step: ``(t, u)``, or ``(t, u, v)`` with a dashpot."""
    return 3 if conn._damping else 2


def replay_records(conn) -> np.ndarray:
    """The records as rows ``(t, u, F, dissipated, work)``: the rows ``(t, u[, v])``
    replayed on a copy of the joint taken where the records start (cached, extended
    incrementally); a dashpot adds ``c v`` to the force and ``c (v0 + v) / 2 (u - u0)`` per
    step to the dissipation and the work (as the Python law books it).
    """
    raw = conn._rec
    w = stride(conn)
    n = len(raw) // w
    cache = conn._replay
    if cache is None or cache[1] > n:
        cache = conn._replay = [copy.deepcopy(conn._snapshot), 0, np.empty((0, 5)), None]
    j, done, table, dash = cache
    if done < n:
        new = np.empty((n - done, 5))
        rows = raw[w * done : w * n].tolist()
        trial, commit = j.trial, j.commit
        c = conn._damping
        for k in range(n - done):
            t, u = rows[w * k], rows[w * k + 1]
            F = trial(u)[0]
            commit()
            if c:
                v = rows[w * k + 2]
                d = 0.0 if dash is None else dash[2] + c * 0.5 * (dash[1] + v) * (u - dash[0])
                dash = (u, v, d)
                F += c * v
            else:
                d = 0.0
            new[k] = (t, u, F, j.dissipated_energy + d, j.work + d)
        table = np.concatenate([table, new]) if done else new
        cache[1], cache[2], cache[3] = n, table, dash
    return table
