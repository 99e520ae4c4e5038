"""The checks every tracker settings group runs when made (:mod:`.settings`): a bad value
raises :class:`~depthtrack.errors.InputError` naming the field."""
from __future__ import annotations

from ..errors import InputError


def check(ok: bool, message: str) -> None:
    if not ok:
        raise InputError(None, message)


def positive(group, *names, allow_zero=False):
    for n in names:
        v = getattr(group, n)
        check(v >= 0 if allow_zero else v > 0,
               f"{type(group).__name__}.{n} must be {'>= 0' if allow_zero else '> 0'}, not {v!r}")


def one_of(group, name, choices):
    v = getattr(group, name)
    check(v in choices, f"{type(group).__name__}.{name} must be one of {', '.join(choices)}, "
                        f"not {v!r}")


def power_of_two(v, name, zero_ok=False):
    check((zero_ok and v == 0) or (4 <= v <= 1024 and not v & (v - 1)),
           f"{name} must be a power of two in 4..1024{' or 0' if zero_ok else ''}, not {v!r}")
