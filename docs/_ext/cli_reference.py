"""``.. femrub-cli::``: every command of ``femrub`` from its argparse parser, at build time."""

from __future__ import annotations

import argparse

from docutils import nodes
from docutils.statemachine import StringList
from sphinx.util.docutils import SphinxDirective
from sphinx.util.nodes import nested_parse_with_titles


def _commands(parser: argparse.ArgumentParser, prog: str):
    """Yield ``(command line, parser)`` for the parser and each subcommand, depth first."""
    yield prog, parser
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            helps = {a.dest: a.help for a in action._choices_actions}
            for name, sub in action.choices.items():
                sub.description = sub.description or helps.get(name)
                yield from _commands(sub, f"{prog} {name}")


def cli_lines() -> list[str]:
    """reStructuredText of every command: its one-line purpose and its ``--help``."""
    from femrub.app.cli import build_parser

    lines = []
    for command, parser in _commands(build_parser(), "femrub"):
        parser.prog = command
        parser.formatter_class = lambda prog: argparse.HelpFormatter(prog, width=90)
        title = f"``{command}``"
        lines += [title, "-" * len(title), ""]
        if parser.description:
            lines += [" ".join(parser.description.split()), ""]
        lines += [".. code-block:: text", ""]
        lines += [f"   {line}".rstrip() for line in parser.format_help().splitlines()]
        lines.append("")
    return lines


class FemrubCli(SphinxDirective):
    """Insert the help of every ``femrub`` command."""

    def run(self):
        container = nodes.container()
        nested_parse_with_titles(self.state, StringList(cli_lines(), "femrub.app.cli"), container)
        return container.children


def setup(app):
    app.add_directive("femrub-cli", FemrubCli)
    return {"version": "1", "parallel_read_safe": True}
