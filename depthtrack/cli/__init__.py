"""Command-line entry point: argument parsing only; every command calls the library.

Each command family lives in its own module with a ``register(subparsers)``
function that adds its parser and sets ``func`` to a callable taking the parsed
arguments and returning an exit status.
"""
from __future__ import annotations

import importlib
import sys

from ..errors import InputError
from ..render.context import GLUnavailableError
from .args import Parser, print_error

#: Modules under ``depthtrack.cli`` that contribute commands, in ``--help`` order.
COMMAND_MODULES = ("demo", "synth", "convert", "track", "export", "evaluate", "swim", "bench")


def build_parser() -> Parser:
    parser = Parser(
        prog="depthtrack",
        description="Markerless human motion capture from depth cameras, and learned "
                    "cyclic motion models for swimmers.",
    )
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMAND_MODULES:
        try:
            module = importlib.import_module(f"{__name__}.{name}")
        except ModuleNotFoundError as exc:
            if exc.name == f"{__name__}.{name}":
                continue
            raise
        module.register(subparsers)
    return parser


def main(argv=None) -> int:
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:            # --help (0) or a one-line argparse error (2)
        return exc.code if isinstance(exc.code, int) else 2
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        return int(args.func(args) or 0)
    except InputError as exc:
        print_error(args.command, exc)
        return 2
    except OSError as exc:
        # the disk filled up, a device went away...: not the user's input, still one line
        from ..io.atomic import describe_os_error
        where = f"{exc.filename}: " if exc.filename else ""
        print_error(args.command, f"{where}{describe_os_error(exc)}")
        return 1
    except GLUnavailableError as exc:          # the machine lacks headless OpenGL: say what to install
        print_error(args.command, exc)
        return 1
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
