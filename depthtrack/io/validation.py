"""Checks of what users hand in: PNG structure, sequence.json ranges, ground-truth coverage.

Pure checks that raise :class:`~depthtrack.errors.InputError` with one line naming the
file, the problem and, for numbers, the allowed range. Used by
:mod:`depthtrack.io.sequence`.
"""
from __future__ import annotations

import contextlib
import math
import os
import struct
import zlib

import numpy as np

from ..errors import InputError

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def check_png_chunks(path, data: bytes) -> None:
    """Walk the chunks (length, type, CRC) up to IEND, so that a truncated or corrupt PNG is
    refused here in one line instead of by libpng, which also prints to stderr."""
    if data[:8] != PNG_SIGNATURE:
        raise InputError(path, "not a PNG file")
    pos, n = 8, len(data)
    while True:
        if pos + 12 > n:
            raise InputError(path, f"truncated PNG ({n} bytes, no IEND chunk)")
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        end = pos + 12 + length
        if end > n:
            raise InputError(path, f"truncated PNG (chunk {kind.decode('latin-1')!r} ends past the "
                                   f"file's {n} bytes)")
        crc = struct.unpack(">I", data[end - 4:end])[0]
        if zlib.crc32(data[pos + 4:end - 4]) != crc:
            raise InputError(path, f"corrupt PNG (bad checksum in chunk {kind.decode('latin-1')!r})")
        if kind == b"IEND":
            return
        pos = end


@contextlib.contextmanager
def stderr_silenced():
    """Send file descriptor 2 to /dev/null for the duration (C libraries write there)."""
    try:
        saved = os.dup(2)
    except OSError:
        yield
        return
    try:
        with open(os.devnull, "wb") as null:
            os.dup2(null.fileno(), 2)
        yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)


def finite_positive(value, what, path):
    try:
        value = float(value)
    except (TypeError, ValueError):
        raise InputError(path, f"{what} is not a number ({value!r})") from None
    if not (math.isfinite(value) and value > 0):
        raise InputError(path, f"{what} must be a positive finite number, not {value!r}")
    return value


#: Allowed ranges of sequence.json fields: (low, high), both included.
META_RANGES = {"fps": (0.1, 1000.0), "depth_scale": (1e-6, 1.0), "width": (1, 16384),
               "height": (1, 16384), "fx": (1.0, 1e5), "fy": (1.0, 1e5),
               "subject.height_m": (0.5, 2.5)}


def in_range(value, what, path, shown=None):
    lo, hi = META_RANGES[what]
    if not lo <= value <= hi:
        raise InputError(path, f"{shown or what} is {value!r}, allowed {lo:g} to {hi:g}")
    return value


def check_camera_fields(cam: dict, path) -> None:
    """Whole-pixel sizes and sane intrinsics before :class:`Camera` sees them."""
    for key in ("width", "height"):
        if key not in cam:
            continue
        v = cam[key]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v != int(v):
            raise InputError(path, f"camera.{key} must be a whole number of pixels, not {v!r}")
        in_range(int(v), key, path, f"camera.{key}")
    for key in ("fx", "fy", "cx", "cy"):
        if key not in cam:
            continue
        v = cam[key]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise InputError(path, f"camera.{key} must be a finite number, not {v!r}")
        if key in ("fx", "fy"):
            lo, hi = META_RANGES[key]
            if not lo <= v <= hi:
                raise InputError(path, f"camera.{key} is {v!r} pixels, allowed {lo:g} to {hi:g}")
    for key, size in (("cx", "width"), ("cy", "height")):
        if key in cam and size in cam and not -cam[size] <= cam[key] <= 2 * cam[size]:
            raise InputError(path, f"camera.{key} is {cam[key]!r}, allowed -{size} to 2 x {size} "
                                   f"(-{cam[size]:g} to {2 * cam[size]:g})")


def check_covers(path, points) -> None:
    """Ground truth that stops before the sequence does was cut short: refuse it (scoring the
    missing frames as unknown would report a wrong figure without a word)."""
    known = np.flatnonzero(np.isfinite(points).all(axis=-1).any(axis=-1))
    n = len(points)
    last = int(known[-1]) if len(known) else None
    if last is None:
        raise InputError(path, "holds no coordinates")
    if last < n - 1:
        raise InputError(path, f"ends at frame {last}, but the sequence has frames 0 to {n - 1} "
                               f"(cut short?)")


__all__ = ["PNG_SIGNATURE", "check_png_chunks", "stderr_silenced", "finite_positive", "in_range", "check_camera_fields",
           "check_covers", "META_RANGES"]
