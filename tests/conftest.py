"""Shared test configuration: the hypothesis settings profiles, and the compiled kernels
warmed once before the xdist workers start.

The number of examples is bounded so that the suite stays fast: ``ci`` (default, 40 examples,
no deadline, derandomised) or ``long`` (1000 examples), chosen with the environment variable
``IWAN_HYPOTHESIS_PROFILE`` (or any count with ``IWAN_HYPOTHESIS_EXAMPLES``, which
``benchmarks/bench_properties.py`` sets). Shared helpers and strategies live in
``tests/_helpers.py`` (one copy each).

With xdist (``pytest -n 2``) the controller compiles the package's numba kernels into their
on-disk cache before the workers start (``tests/_warm_kernels.py``): in a fresh clone the
cache is cold and each worker compiled the same kernels again while its tests waited.
"""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
from pathlib import Path

from hypothesis import HealthCheck, settings

ROOT = Path(__file__).resolve().parents[1]


def _warm_kernel_caches() -> None:
    """Run ``tests/_warm_kernels.py`` for each copy of the package the suite imports, at once:
    the one ``import iwan_element`` finds here (the workers' copy) and, when it is another
    one (a non-editable install, as in CI), the checkout's source tree, which the README
    recipes and the fresh-process tests import from the repository's root. A failure is
    reported and left to the tests themselves.
    """
    spec = importlib.util.find_spec("iwan_element")
    here = Path(spec.origin).resolve().parent if spec and spec.origin else None
    envs = [dict(os.environ)]
    if here != ROOT / "iwan_element":
        path = os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))
        envs.append({**os.environ, "PYTHONPATH": path})
    script = str(Path(__file__).with_name("_warm_kernels.py"))
    runs = [
        subprocess.Popen(
            [sys.executable, script],
            cwd=ROOT,
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        for env in envs
    ]
    for run in runs:
        out, err = run.communicate(timeout=600)
        if run.returncode != 0:
            sys.stderr.write(f"warming the compiled kernels failed:\n{err[-2000:]}\n")


def pytest_configure(config):
    """In the xdist controller only (a worker has ``workerinput``), before it starts the
    workers: the kernels compiled once into the cache they all load from."""
    if hasattr(config, "workerinput") or not getattr(config.option, "numprocesses", None):
        return
    if config.option.collectonly:
        return
    _warm_kernel_caches()


settings.register_profile(
    "ci",
    max_examples=40,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.too_slow],
)
settings.register_profile(
    "long", max_examples=1000, deadline=None, suppress_health_check=[HealthCheck.too_slow]
)
if os.environ.get("IWAN_HYPOTHESIS_EXAMPLES"):
    settings.register_profile(
        "custom",
        max_examples=int(os.environ["IWAN_HYPOTHESIS_EXAMPLES"]),
        deadline=None,
        suppress_health_check=[HealthCheck.too_slow],
    )
    settings.load_profile("custom")
else:
    settings.load_profile(os.environ.get("IWAN_HYPOTHESIS_PROFILE", "ci"))
