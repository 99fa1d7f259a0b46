"""Package discovery for setuptools (everything else is in pyproject.toml).

``models/`` sits beside the package in the source tree and installs as ``iwan_element.models``
(``[tool.setuptools.package-dir]``). ``[tool.setuptools.packages.find]`` cannot rename a found
folder, so the packages are found here: every folder holding an ``__init__.py`` under
``iwan_element/`` and under ``models/`` (prefixed ``iwan_element.models``), whatever the rooms.
"""

from setuptools import find_packages, setup

MODELS = "iwan_element.models"

setup(
    packages=[
        *find_packages(include=["iwan_element", "iwan_element.*"]),
        MODELS,
        *(f"{MODELS}.{name}" for name in find_packages("models")),
    ]
)
