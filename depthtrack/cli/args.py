"""Argument parsing shared by every command: one-line errors and range-checked numbers.

``Parser`` prints argparse's errors as one line (``depthtrack track: error: ...``,
exit status 2) instead of the usage block. :func:`number` and :func:`integer` make
``type=`` callables that refuse anything outside the allowed range and say the range.
"""
from __future__ import annotations

import argparse
import math
import sys


class Parser(argparse.ArgumentParser):
    """An ArgumentParser whose errors are one line on stderr with exit status 2."""

    def error(self, message):
        message = " ".join(str(message).split())
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def _range_text(lo, hi, lo_open, hi_open) -> str:
    if hi is None:
        return f"{'>' if lo_open else '>='} {lo:g}"
    if lo is None:
        return f"{'<' if hi_open else '<='} {hi:g}"
    return f"in {'(' if lo_open else '['}{lo:g}, {hi:g}{')' if hi_open else ']'}"


def number(lo=None, hi=None, lo_open=False, hi_open=False):
    """``type=`` for a finite float in a range; the message gives the range.

    ``lo_open``/``hi_open`` exclude the bound (``number(0, lo_open=True)``: positive).
    """
    allowed = _range_text(lo, hi, lo_open, hi_open)

    def parse(text):
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a number (allowed: {allowed})") from None
        ok = math.isfinite(value)
        if ok and lo is not None:
            ok = value > lo if lo_open else value >= lo
        if ok and hi is not None:
            ok = value < hi if hi_open else value <= hi
        if not ok:
            raise argparse.ArgumentTypeError(f"{text} is out of range (allowed: {allowed})")
        return value

    parse.__name__ = "number"
    return parse


def integer(lo=None, hi=None):
    """``type=`` for a whole number in ``[lo, hi]``; the message gives the range."""
    allowed = _range_text(lo, hi, False, False)

    def parse(text):
        try:
            value = int(str(text).strip())
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a whole number (allowed: {allowed})") from None
        if (lo is not None and value < lo) or (hi is not None and value > hi):
            raise argparse.ArgumentTypeError(f"{text} is out of range (allowed: {allowed})")
        return value

    parse.__name__ = "integer"
    return parse


#: Common ranges, defined once.
POSITIVE = number(0, lo_open=True)
SEED = integer(0, 2**32 - 1)
FPS = number(0, 1000, lo_open=True)
SUBJECT_HEIGHT = number(0.5, 2.5)           # metres: the human range the body model covers
THREADS = integer(1, 256)


def add_force(parser, what: str = "the output directory") -> None:
    """``--force``: replace an existing non-empty directory that is not an earlier output."""
    parser.add_argument("--force", action="store_true",
                        help=f"replace {what} even when it is a non-empty directory that does not "
                             f"hold an earlier output of this command")


def check_output(args, attr: str, inputs=(), kind: str = "dir", command: str | None = None,
                 option: str | None = None):
    """:func:`depthtrack.io.outputs.check_output` for ``args.<attr>`` (skipped when unset)."""
    from ..io.outputs import check_output as check

    path = getattr(args, attr, None)
    if path is None:
        return None
    option = option or "--" + attr.replace("_", "-")
    return check(path, inputs=inputs, kind=kind, force=getattr(args, "force", False),
                 command=command or args.command, option=option)


def print_error(command: str, text: str) -> None:
    """One line on stderr: ``depthtrack COMMAND: text``."""
    print(f"depthtrack {command}: {' '.join(str(text).split())}", file=sys.stderr)
