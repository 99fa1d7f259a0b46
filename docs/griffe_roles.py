"""A griffe extension for the documentation site: the docstrings' Sphinx roles as code.

The docstrings name other objects the numpydoc way (``:func:`~iwan_element.fit_loops```,
``:class:`IwanParameters```, ...), which Markdown would show literally. Each role becomes an
inline code span of the name (the last part where the target starts with ``~``), before the
numpy-style parser reads the docstring.
"""

from __future__ import annotations

import re
from typing import Any

import griffe

ROLE = re.compile(r":(?:py:)?(?:func|meth|class|mod|attr|data|obj|exc|const):`(~?)([^`]+)`")


def _code(match: re.Match[str]) -> str:
    short, target = match.groups()
    return f"`{target.rsplit('.', 1)[-1] if short else target}`"


class SphinxRoles(griffe.Extension):
    """Replace ``:role:`target``` by ```target``` in every docstring griffe reads."""

    def on_instance(self, *, obj: griffe.Object, **kwargs: Any) -> None:
        """Rewrite the roles of one object's docstring (modules, classes, functions, ...)."""
        if obj.docstring is not None:
            obj.docstring.value = ROLE.sub(_code, obj.docstring.value)
