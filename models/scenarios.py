"""Scenarios for the jointed beam: the paper's quasi-static test, free decay, forced response.

Each scenario builds its own model from a :class:`~iwan_element.models.jointed_beam.JointedBeamConfig`
and returns a result object with numpy arrays, metadata and a JSON-safe ``summary()``.

* :func:`quasi_static_test`: beam A clamped, beam B's end gripped and driven axially with
  ``u(t) = u0 sin(2 pi f t)`` (0.02 Hz, 0.1 mm by default), solved with Exudyn's static solver
  one load step per sample (inertia is irrelevant at 0.02 Hz); machine force vs displacement
  and joint force vs slip.
* :func:`modal_analysis`: linearised modes with the joint at its stiffness ``KT`` and the
  closed-form prediction of the amplitude-dependent frequency and damping of a mode
  (single-mode equivalent linearisation with the joint's secant stiffness, paper eq. 24, and
  dissipation per cycle, paper eq. 17)::

      w(q)^2 = w_lin^2 - sum_i g_i^2 (KT_i - K_sec,i(|g_i| q))
      zeta(q) = sum_i D_i(|g_i| q) / (2 pi w(q)^2 q^2)

  where ``q`` is the mass-normalised modal amplitude and ``g_i`` the slip at contact point
  ``i`` per unit ``q``.
* :func:`free_decay`: released from rest in the first bending mode's shape at several
  levels, integrated with generalized-alpha at spectral radius 1 (no numerical damping);
  amplitude-dependent frequency and damping extracted cycle by cycle from the tip response,
  next to the prediction and to the same run with a linear joint of stiffness ``KT``.
* :func:`forced_response`: harmonic tip force at several levels, stepped through the first
  resonance with continuation; steady amplitude per frequency and the resonance peak.
"""
from __future__ import annotations

from ._forced import ForcedResponseResult, forced_response
from ._free_decay import DecayRun, FreeDecayResult, decay_analysis, free_decay
from ._linear_modes import ModalResult, modal_analysis
from ._quasi_static import QuasiStaticResult, quasi_static_test
from ._scenario_settings import _settings  # noqa: F401  (solver settings shared with transient)

__all__ = ["QuasiStaticResult", "quasi_static_test", "ModalResult", "modal_analysis",
           "DecayRun", "FreeDecayResult", "free_decay", "decay_analysis",
           "ForcedResponseResult", "forced_response"]
