"""MkDocs hook: the command-line reference (docs/cli.md) generated from the argparse parser itself, so it can
never disagree with what ``pcsuite --help`` prints."""
from __future__ import annotations

import argparse
import os

MARKER = "<!-- generated: the command-line reference -->"


def _parsers(parser: argparse.ArgumentParser, prefix: str):
    """(command line, parser) for the top level and every subcommand, nested ones (``mech simulate``) included."""
    yield prefix, parser
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield from _parsers(sub, f"{prefix} {name}")


def reference() -> str:
    os.environ["COLUMNS"] = "110"                 # argparse wraps to the terminal: the same page on every machine
    from validation.cli import build_parser
    blocks = []
    for command, parser in _parsers(build_parser(), "pcsuite"):
        level = "##" if command.count(" ") <= 1 else "###"
        blocks.append(f"{level} `{command}`\n\n```text\n{parser.format_help().rstrip()}\n```\n")
    return "\n".join(blocks)


def on_page_markdown(markdown, page, config, files):
    if MARKER in markdown:
        return markdown.replace(MARKER, reference())
    return markdown
