"""MkDocs hook: the docstrings' Sphinx roles (``:class:`~a.b.C```) as code, linked where documented.

The code's docstrings are Google style with reStructuredText roles for cross-references, which
Markdown renders as ``:class:<code>~a.b.C</code>``. This turns each into ``<code>C</code>`` (the
``~`` form) or ``<code>a.b.C</code>``, and a fully qualified ``pipefollow.…`` name into an
*optional* cross-reference of mkdocs-autorefs: a link where the object is on the site, plain code
where it is not (no warning either way).
"""

from __future__ import annotations

import re

ROLE = re.compile(r":(?:class|func|meth|mod|data|attr|exc|obj|const):<code>(~?)([\w.]+)</code>")


def _replace(match: re.Match[str]) -> str:
    short, target = match.group(1), match.group(2)
    shown = target.rsplit(".", 1)[-1] if short else target.lstrip(".")
    code = f"<code>{shown}</code>"
    if target.startswith("pipefollow."):
        return f'<autoref identifier="{target}" optional>{code}</autoref>'
    return code


def on_page_content(html: str, **kwargs) -> str:
    """The page's HTML with the roles replaced (before autorefs resolves its references)."""
    return ROLE.sub(_replace, html)
