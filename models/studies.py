"""Ready-made ensemble tasks for parameter studies of the lap-jointed beam specimens (here,
beside the models they run, so that the ensemble runner below never imports the models).

:func:`specimen_curve_task` runs the quasi-static modal analysis
(:func:`iwan_element.models.modal.modal_amplitude_curve`, docs/equations.md section 7) of a
:class:`~iwan_element.models.specimens.Specimen` with some of its inputs changed, so that
preload, friction coefficient, bolt count or an interface parameter can be swept with
:func:`~iwan_element.ensemble.run_ensemble`::

    from functools import partial
    task = partial(specimen_curve_task, specimen=preset("example"), amplitude=X)
    result = run_ensemble(task, parameter_grid(preload=[10e3, 20e3, 30e3]))

"""

from __future__ import annotations

from typing import Any

import numpy as np

from .modal import modal_amplitude_curve

__all__ = ["specimen_curve_task", "with_changes"]


def with_changes(specimen, params: dict) -> Any:
    """The specimen with ``params`` applied: any ``Specimen`` or ``InterfaceModel`` field by
    name (``preload`` [N], ``friction`` [-], ``chi``, ``stiffness_per_area``, ...) and
    ``n_bolts``, which places that many bolts evenly along the lap (centres at
    ``overlap (k + 1/2) / n_bolts``; an assumption of the study, not of a real specimen).
    """
    changes = dict(params)
    n = changes.pop("n_bolts", None)
    if n is not None:
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
            raise ValueError(f"n_bolts must be an integer >= 1, got {n!r}")
        L = specimen.overlap
        changes["bolt_positions"] = tuple(L * (k + 0.5) / int(n) for k in range(int(n)))
    return specimen.replace(**changes)


def specimen_curve_task(params: dict, rng, *, specimen, amplitude=None, mode: int = 1) -> dict:
    """One ensemble task: the QSMA amplitude curve of ``specimen`` changed by ``params``.

    Parameters
    ----------
    params : dict
        Changes, see :func:`with_changes`.
    rng : numpy.random.Generator
        Unused (the model is deterministic).
    specimen : Specimen, keyword-only
        The base specimen (for instance ``iwan_element.models.specimens.preset("example")``).
    amplitude : array_like, optional, keyword-only
        Displacement amplitudes at the sensor [m]; default the specimen's documented range.
    mode : int, keyword-only
        Elastic mode number.

    Returns
    -------
    dict
        ``amplitude`` [m], ``frequency`` [Hz] and ``damping_ratio`` [-] arrays, and the scalars
        ``f_linear`` (frequency at the smallest amplitude) [Hz], ``frequency_drop``
        (``1 - f(X_max) / f(X_min)``) and ``damping_ratio_max`` [-].
    """
    curve = modal_amplitude_curve(with_changes(specimen, params), mode=mode, amplitude=amplitude)
    f = np.asarray(curve.frequency, float)
    z = np.asarray(curve.damping_ratio, float)
    return {
        "amplitude": np.asarray(curve.amplitude, float),
        "frequency": f,
        "damping_ratio": z,
        "f_linear": float(f[0]),
        "frequency_drop": float(1.0 - f[-1] / f[0]),
        "damping_ratio_max": float(z.max()),
    }
