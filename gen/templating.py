"""The Jinja2 environment over the installed ``wirecal.templates`` package.

Templates are found through :mod:`importlib.resources`, so they load the same from a
wheel, an editable install or a source checkout. Rendering is deterministic and strict:
an undefined variable is an error, never an empty string.
"""

from __future__ import annotations

from functools import cache
from importlib import resources

import jinja2


class _ResourceLoader(jinja2.BaseLoader):
    def get_source(self, environment: jinja2.Environment, template: str):
        node = resources.files("wirecal.templates")
        for part in template.split("/"):
            node = node.joinpath(part)
        if not node.is_file():
            raise jinja2.TemplateNotFound(template)
        return node.read_text(encoding="utf-8"), None, lambda: True


@cache
def environment() -> jinja2.Environment:
    """Return the Jinja2 environment of the packaged templates (strict, no autoescape)."""
    return jinja2.Environment(
        loader=_ResourceLoader(),
        undefined=jinja2.StrictUndefined,
        keep_trailing_newline=True,
        trim_blocks=True,
        lstrip_blocks=True,
        autoescape=False,
    )


def render(template: str, **context: object) -> str:
    """Render a template from ``wirecal.templates`` with the given variables."""
    return environment().get_template(template).render(**context)
