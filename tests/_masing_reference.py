"""Plain-Python reference of the extended Masing rules for the continuous Iwan joint (test use
only; the package runs the compiled kernel of ``iwan_element.core.masing``).

Written from the rules, not from the kernel: a list of reversal points ``(u_r, F_r)``; a
reversal pushes the turning point unless it lies within ``tol`` of the previous reversal
(which is then forgotten); a move that passes the reversal below the top closes that loop
and forgets both points (Madelung), and passing ``-u_r`` of the last point returns to the
virgin curve. Forces and tangents come from the closed forms ``backbone`` and
``tangent_stiffness`` (Segalman 2005, eq. 17 and its derivative): ``F_r + 2 F_bb((u - u_r)/2)``
on a branch, ``F_bb(u)`` on the virgin curve.
"""

from __future__ import annotations

import numpy as np

from iwan_element import backbone, tangent_stiffness


def reference_history(u, p, tol=0.0):
    """Force [N], tangent [N/m] and anchor sample (-1: virgin curve) of every sample of the
    displacement history ``u`` [m] from the virgin state; ``tol``: absolute reversal
    tolerance [m]."""
    stack = []  # (u_r, F_r, sample index of the turning point)
    uc, Fc, ic = 0.0, 0.0, -1
    F = np.empty(len(u))
    K = np.empty(len(u))
    anchor = np.empty(len(u), dtype=int)
    for i, x in enumerate(np.asarray(u, float).tolist()):
        if x != uc:
            going_up = x > uc
            ref = stack[-1][0] if stack else 0.0
            branch_up = uc > ref
            branch_down = uc < ref
            if (going_up and branch_down) or (not going_up and branch_up):
                if abs(uc - ref) <= tol:
                    if stack:
                        stack.pop()
                else:
                    stack.append((uc, Fc, ic))
            while stack:
                below = stack[-2][0] if len(stack) >= 2 else -stack[-1][0]
                passed = x >= below if going_up else x <= below
                if not passed:
                    break
                del stack[-2:]
        if stack:
            ur, Fr, ia = stack[-1]
            arg = (x - ur) / 2.0
            F[i] = Fr + 2.0 * backbone(arg, p)
            K[i] = tangent_stiffness(arg, p)
            anchor[i] = ia
        else:
            F[i] = backbone(x, p)
            K[i] = tangent_stiffness(x, p)
            anchor[i] = -1
        uc, Fc, ic = x, F[i], i
    return F, K, anchor
