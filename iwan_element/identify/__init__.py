"""Identification, by the data a tester holds (bottom to top; a room imports only rooms below
it).

The rooms:

* :mod:`.loops`: force-displacement loops (a quasi-static or cyclic test): the loop and
  dissipation fits of the four parameters, their identifiability and uncertainty, the
  force-model fit, cycles, record noise and the synthetic test records;
* :mod:`.files`: reading a test from a file with its units (CSV, UFF) and the unit checks of
  vibration data;
* :mod:`.modal`: amplitude-dependent frequency and damping curves (:class:`AmplitudeCurve`)
  and what is fitted to them (the modal Iwan fit), linear modal targets, damped-sinusoid
  poles;
* :mod:`.decays`: free decays (a ring-down after a hammer blow): amplitude curves, the direct
  decay fit, the linear modes of a multi-sensor decay, clipping, and the package's one
  band-pass + Hilbert envelope (:mod:`.decays.envelope`);
* :mod:`.sweeps`: forced response (sine sweeps, stepped sine) to amplitude curves and modes.
"""
