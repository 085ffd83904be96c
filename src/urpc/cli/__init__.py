"""Command-line interface: ``urpc COMMAND ...`` (``urpc --help`` lists the commands).

Contract for every command: exit code 0 on success, 2 for bad user input with a single line on
stderr starting with ``error:`` (no traceback); ``--json`` prints one JSON object on stdout.
Each command group lives in its own module with a ``register(commands)`` function that adds its
commands, each with :func:`~urpc.cli.common.add_command` (its name, ``handler`` and help texts);
:data:`COMMAND_MODULES` lists the modules in ``--help`` order.
"""

from __future__ import annotations

import argparse
import errno
import sys
import warnings
from collections.abc import Sequence

from .. import __version__
from ..errors import UrpcError
from . import (
    bench,
    campaign,
    certify,
    demo,
    identify,
    init,
    inspect,
    run,
    simulate,
    virtual_robot,
)
from .common import EXIT_INPUT, EXIT_OK, Parser, add_subcommands, one_line

COMMAND_MODULES = [
    inspect, init, identify, simulate, certify, demo, campaign, bench, run, virtual_robot,
]  # fmt: skip


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(
        prog="urpc",
        description=(
            "Ultimate robust performance control: synthesize a passivity-based tracking controller "
            "whose gains adapt until the joint error stays below epsilon, from a URDF and a file "
            "of parameter intervals; bound the model-mismatch torque with interval methods; "
            "simulate and compare with the r-alpha baseline."
        ),
        epilog="Exit codes: 0 success, 2 bad input. Docs: docs/ in the source tree.",
    )
    parser.add_argument("--version", action="version", version=f"urpc {__version__}")
    commands = add_subcommands(parser, "command", "COMMAND")
    for module in COMMAND_MODULES:
        module.register(commands)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI; returns the exit code (also used by the ``urpc`` console script)."""
    try:
        parser = build_parser()
        args = parser.parse_args(argv)
        if args.command is None:  # a bare `urpc`: the command list, as `urpc --help`
            parser.print_help()
            return EXIT_OK
        with warnings.catch_warnings():
            warnings.showwarning = _print_warning
            return args.handler(args)
    except UrpcError as exc:
        print(f"error: {one_line(str(exc))}", file=sys.stderr)
        return EXIT_INPUT
    except BrokenPipeError:  # e.g. `urpc robots | head`
        sys.stderr.close()
        return EXIT_OK
    except OSError as exc:  # the file system refused a path no command checks (a name too long)
        print(f"error: {os_error_line(exc)}", file=sys.stderr)
        return EXIT_INPUT
    except KeyboardInterrupt:
        print("error: interrupted", file=sys.stderr)
        return 130


def os_error_line(exc: OSError) -> str:
    """One line for a file system's refusal: the path (its ends, when long), the reason and,
    for a name too long, the limits."""
    name = "" if exc.filename is None else str(exc.filename)
    if len(name) > 120:
        name = f"{name[:60]}...{name[-40:]} ({len(name)} characters)"
    reason = exc.strerror or str(exc)
    if exc.errno == errno.ENAMETOOLONG:
        reason += ": give a shorter path (a name of at most 255 bytes, a path of at most 4096)"
    return one_line(f"{name}: {reason}" if name else reason)


def _print_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """Python warnings as the CLI's one-line ``warning:`` messages on stderr."""
    print(f"warning: {one_line(str(message))}", file=sys.stderr)
