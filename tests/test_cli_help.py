"""The project's rule: every command and option has --help text with its default.

Walks the whole ``mcrt`` parser, nested subcommands included (``mcrt reference build``),
and lists every argument whose help is missing, or, for an optional argument, does not
state its default (the word "default"; a flag that takes no value says "(default: off)").
"""

from __future__ import annotations

import argparse

from mcrt.cli import build_parser


def _walk(parser: argparse.ArgumentParser, prog: str):
    """Yield (command path, action) for every argument of ``parser`` and its subparsers."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield from _walk(sub, f"{prog} {name}")
        else:
            yield prog, action


def _offenders() -> list[str]:
    offenders = []
    for prog, action in _walk(build_parser(), "mcrt"):
        if isinstance(action, argparse._HelpAction):
            continue
        name = "/".join(action.option_strings) or action.dest
        text = action.help
        if text is argparse.SUPPRESS:
            offenders.append(f"{prog} {name}: help is suppressed")
        elif not text or not str(text).strip():
            offenders.append(f"{prog} {name}: no help text")
        elif action.option_strings and "default" not in str(text).lower():
            offenders.append(f"{prog} {name}: help does not state the default: {text!r}")
    return offenders


def test_walk_reaches_nested_subcommands():
    progs = {prog for prog, _ in _walk(build_parser(), "mcrt")}
    for expected in ("mcrt render", "mcrt compare", "mcrt reference build", "mcrt reference verify"):
        assert expected in progs


def test_every_argument_has_help_with_its_default():
    offenders = _offenders()
    assert not offenders, f"{len(offenders)} arguments break the --help rule:\n" + "\n".join(offenders)
