"""Command-line entry point: argument parsing only; every command calls the library.

Each command family lives in its own module with a ``register(subparsers)``
function that adds its parser and sets ``func`` to a callable taking the parsed
arguments and returning an exit status.
"""
from __future__ import annotations

import argparse
import importlib
import sys

from ..errors import InputError

#: Modules under ``depthtrack.cli`` that contribute commands, in ``--help`` order.
COMMAND_MODULES = ("demo", "synth", "track", "export", "evaluate", "swim", "bench")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
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
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        return int(args.func(args) or 0)
    except InputError as exc:
        print(f"depthtrack {args.command}: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
