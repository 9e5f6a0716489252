"""``.. scene-keys::``: every scene key from ``femrub.scene.schema`` (type, unit, default, bounds).

The table is made from the schema the validator uses, at build time, so it cannot drift from
what ``femrub check`` accepts.
"""

from __future__ import annotations

import math

from docutils import nodes
from docutils.statemachine import StringList
from sphinx.util.docutils import SphinxDirective
from sphinx.util.nodes import nested_parse_with_titles


def _literal(value) -> str:
    if isinstance(value, bool):
        return "``true``" if value else "``false``"
    if isinstance(value, float):
        if math.isinf(value):
            return "``inf``" if value > 0 else "``-inf``"
        return f"``{value:g}``"
    if isinstance(value, str):
        return f'``"{value}"``' if value else '``""``'
    if isinstance(value, list | tuple):
        return "``[" + ", ".join(_literal(v).strip("`") for v in value) + "]``"
    return f"``{value!r}``"


def default_text(spec, required) -> str:
    """The default of a key as the docs show it."""
    if spec.default is required:
        return "required"
    if spec.default is None:
        return "chosen by the builder"
    return _literal(spec.default)


def bounds_text(spec) -> str:
    """Allowed values of a key: its interval (as the validator's messages word it) and words."""
    parts = [spec._range().strip()] if spec.lo is not None or spec.hi is not None else []
    if spec.choices:
        words = ", ".join(_literal(c) for c in spec.choices)
        parts.append(("one of " if spec.kind == "choice" else "or ") + words)
    return "; ".join(parts) or "—"


def _prose(text: str) -> str:
    """Plain text of a schema description, its reStructuredText specials escaped."""
    for char in "\\*`|_":
        text = text.replace(char, "\\" + char)
    return text


def _cell(text: str) -> str:
    return " ".join(str(text).split()) or "—"


def _table(rows: list[list[str]]) -> list[str]:
    lines = [".. list-table::", "   :header-rows: 1", "   :widths: 26 8 10 14 18 24", ""]
    head = ["key", "type", "unit (SI)", "default", "allowed", "meaning"]
    for row in [head, *rows]:
        lines.append(f"   * - {_cell(row[0])}")
        lines += [f"     - {_cell(c)}" for c in row[1:]]
    return [*lines, ""]


def scene_key_lines() -> list[str]:
    """reStructuredText of every key, one table per top-level section."""
    from femrub.scene.schema import SCHEMA, TOP, schema_rows
    from femrub.scene.spec import REQUIRED, Variant

    lines = []
    for section, table in [("top level", TOP), *((f"[{k}]", {k: v}) for k, v in SCHEMA.items())]:
        rows = []
        for key, spec, variant in schema_rows(table):
            if isinstance(spec, Variant):
                choices = ", ".join(_literal(c) for c in spec.variants)
                rows.append(
                    [
                        f"``{key}``",
                        "choice",
                        "-",
                        _literal(spec.default),
                        "one of " + choices,
                        _prose(spec.doc) or "selects the keys below",
                    ]
                )
                continue
            when = f" (when ``{key.split('.')[0]}`` is ``{variant}``)" if variant else ""
            rows.append(
                [
                    f"``{key}``",
                    spec.kind,
                    spec.unit,
                    "—" if "[]" in key and spec.default is None else default_text(spec, REQUIRED),
                    bounds_text(spec),
                    _prose(spec.doc or "") + when,
                ]
            )
        lines += [section, "-" * len(section), "", *_table(rows)]
    return lines


class SceneKeys(SphinxDirective):
    """Insert the table of every scene key."""

    has_content = False

    def run(self):
        container = nodes.container()
        text = StringList(scene_key_lines(), source="femrub.scene.schema")
        nested_parse_with_titles(self.state, text, container)
        return container.children


def setup(app):
    app.add_directive("scene-keys", SceneKeys)
    return {"version": "1", "parallel_read_safe": True}
