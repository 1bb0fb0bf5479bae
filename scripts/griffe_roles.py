"""The docs site's griffe extension: the docstrings' Sphinx roles as links (mkdocs.yml).

The docstrings are numpydoc, written for a reader of the source and for ``help()``: they
cross-reference with Sphinx roles (``:func:`run_step```, ``:class:`~station.plan.StepPlan```,
``:data:`station.rig.DT```) and end a paragraph before a literal block with ``::``. The API
reference (mkdocstrings' Python handler, which reads Markdown) would print the roles as they
are. This extension, run by griffe as it loads the package, rewrites each role as an
*optional* mkdocs-autorefs reference: a link where the API reference has the object, plain
code where it does not (a private helper, a module not in the reference). A name without a
``station.`` prefix is looked up where the docstring is: the class's members, then the
module's (its own objects and what it imports). ``~`` shows the last part only, as in Sphinx.

Enabled in mkdocs.yml: ``extensions: [scripts/griffe_roles.py:SphinxRoles]``.
"""

from __future__ import annotations

import html
import re
from typing import Any

import griffe

ROLE = re.compile(r":(?:py:)?(?:func|class|meth|data|attr|mod|exc|obj|const|term):`([^`]+)`")
"""A Sphinx role and its target (``:func:`name```, ``:py:class:`name```)."""

LITERAL_BLOCK = re.compile(r"(\S)::\n(\s*\n)")
"""reST's ``text::`` before a literal block (Markdown takes the indented block as code)."""


def _lookup(obj: griffe.Object, head: str) -> str | None:
    """The path of ``head`` as seen from ``obj``: a member of its class, else of its module
    (an object defined there, or what the module imports under that name)."""
    scopes = []
    if obj.is_class:
        scopes.append(obj)
    if obj.parent is not None and obj.parent.is_class:
        scopes.append(obj.parent)
    scopes.append(obj.module)
    for scope in scopes:
        member = scope.members.get(head)
        if member is not None:
            return member.target_path if member.is_alias else member.path
    return None


def resolve(obj: griffe.Object, target: str) -> str:
    """The full dotted path a role's target names, seen from ``obj`` (itself when it cannot tell).

    Parameters
    ----------
    obj : griffe.Object
        Where the docstring is.
    target : str
        The role's target without ``~`` and leading dots, e.g. ``run_step``, ``StepReport.plot``.

    Returns
    -------
    str
        ``station.experiment.run_step``; the target itself when it is already full or unknown.
    """
    if target.startswith("station.") or target == "station":
        return target
    head, _, rest = target.partition(".")
    found = _lookup(obj, head)
    return target if found is None else found + ("." + rest if rest else "")


def rewrite(obj: griffe.Object, text: str) -> str:
    """``text`` with its roles as optional autorefs and its ``::`` paragraph ends as ``:``.

    Parameters
    ----------
    obj : griffe.Object
        Where the docstring is (for relative names).
    text : str
        A docstring.

    Returns
    -------
    str
        The docstring in Markdown.
    """

    def one(m: re.Match) -> str:
        target = m.group(1).strip()
        titled = re.fullmatch(r"(.+?)\s*<(.+)>", target)
        if titled:
            title, target = titled.group(1), titled.group(2)
        else:
            short = target.startswith("~")
            target = target.lstrip("~").lstrip(".")
            title = target.rsplit(".", 1)[-1] if short else target
        path = resolve(obj, target.lstrip("~").lstrip("."))
        return (f'<autoref identifier="{html.escape(path)}" optional>'
                f"<code>{html.escape(title)}</code></autoref>")

    return LITERAL_BLOCK.sub(r"\1:\n\2", ROLE.sub(one, text))


class SphinxRoles(griffe.Extension):
    """Rewrite every loaded object's docstring (:func:`rewrite`)."""

    def on_object(self, *, obj: griffe.Object, **kwargs: Any) -> None:
        """Rewrite ``obj``'s docstring, when it has one.

        Parameters
        ----------
        obj : griffe.Object
            An object griffe has loaded.
        **kwargs
            What else griffe passes (the loader).
        """
        if obj.docstring is not None:
            obj.docstring.value = rewrite(obj, obj.docstring.value)
