"""The parser built for the command named first on the line (``cli._parser(only)``).

A command line that starts with a command's name gets a parser with that command's
subparser only. Everything it prints or returns must be what the parser of all commands
gives: the command's help, the parsed arguments of every worked example, the usage and
error lines of bad arguments and their exit code.
"""

from __future__ import annotations

import contextlib
import io
import shlex

import pytest

from orientviz import cli


def _run(parser, words: list[str]) -> tuple[object, str, str]:
    """What ``parse_args`` returns or prints (stdout, stderr) and its exit code."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            result: object = vars(parser.parse_args(words))
        except SystemExit as exc:
            result = ("exit", exc.code)
    return result, out.getvalue(), err.getvalue()


def _same(words: list[str]) -> tuple[object, str, str]:
    full = _run(cli._parser(), words)
    one = _run(cli._parser(words[0] if words else None), words)
    assert one == full, words
    return full


@pytest.mark.parametrize("name", list(cli.COMMANDS))
def test_a_commands_help_and_examples_parse_as_with_every_command(name):
    result, out, _ = _same([name, "--help"])
    assert result == ("exit", 0) and out.startswith("usage: orientviz " + name)
    examples = cli.COMMANDS[name].examples
    assert examples
    for invocation, _ in examples:
        words = shlex.split(invocation)[1:]
        result, _, _ = _same(words)
        assert isinstance(result, dict) and result["command"] == name


@pytest.mark.parametrize(
    "words",
    [
        ["solve"],
        ["solve", "a.json", "--no-such-option"],
        ["solve", "a.json", "--max-iter", "zero"],
        ["solve", "a.json", "extra", "words"],
        ["import-bal"],
        ["view", "--port", "-3"],
        ["reproduce", "geier", "--json", "--wide", "x"],
    ],
    ids=" ".join,
)
def test_bad_arguments_print_and_exit_as_with_every_command(words):
    result, _, err = _same(words)
    assert result == ("exit", 2) and err.startswith("orientviz")


@pytest.mark.parametrize("words", [[], ["--help"], ["--version"], ["no-such-command"], ["solv"]])
def test_a_line_without_a_command_first_gets_every_command(words):
    _same(words)
    assert len(cli._parser(words[0] if words else None)._subparsers._group_actions[0].choices) == len(
        cli.COMMANDS
    )


def test_only_the_named_command_is_built():
    choices = cli._parser("solve")._subparsers._group_actions[0].choices
    assert list(choices) == ["solve"]
