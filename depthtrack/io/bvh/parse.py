"""Parse BVH text: the hierarchy (joints, offsets, per-joint channel orders, end sites) and the motion table.

Accepted as real files have them: CRLF or LF line endings, spaces or tabs anywhere
(``Frames:<TAB>643`` in Daz files), any rotation order per joint (Daz files: root
``Zrotation Yrotation Xrotation``, other joints ``Zrotation Xrotation Yrotation``),
``End Site`` in any case. Every problem is an :class:`InputError` naming the line.
"""
from __future__ import annotations

import math
import os
import re
from pathlib import Path

import numpy as np

from ...errors import InputError
from .motion import BvhMotion
from .names import check_joint_map, read_joint_map, strip_namespace
from .units import infer_units, resolve_units

POSITION_CHANNELS = ("Xposition", "Yposition", "Zposition")
ROTATION_CHANNELS = ("Xrotation", "Yrotation", "Zrotation")
_KNOWN_CHANNELS = POSITION_CHANNELS + ROTATION_CHANNELS


class _Tokens:
    """Whitespace tokens with their 1-based line numbers."""

    def __init__(self, lines, path):
        self.path = path
        self.items = []
        for number, line in enumerate(lines, start=1):
            for tok in line.split():
                self.items.append((tok, number))
        self.pos = 0

    def peek(self):
        return self.items[self.pos][0] if self.pos < len(self.items) else None

    def line(self):
        if self.pos < len(self.items):
            return self.items[self.pos][1]
        return self.items[-1][1] if self.items else 1

    def next(self, what="a token"):
        if self.pos >= len(self.items):
            raise InputError(self.path, f"line {self.line()}: file ends where {what} was expected")
        tok = self.items[self.pos]
        self.pos += 1
        return tok

    def expect(self, word):
        tok, line = self.next(repr(word))
        if tok != word:
            raise InputError(self.path, f"line {line}: expected {word!r}, found {tok!r}")
        return line

    def number(self, what):
        tok, line = self.next(what)
        try:
            value = float(tok)
        except ValueError:
            raise InputError(self.path, f"line {line}: {what} is not a number ({tok!r})") from None
        if not math.isfinite(value):
            raise InputError(self.path, f"line {line}: {what} is not finite ({tok!r})")
        return value


def _parse_hierarchy(tokens: _Tokens):
    names, parents, offsets, channels = [], [], [], []
    end_parents, end_offsets = [], []
    tok, line = tokens.next("'HIERARCHY'")
    if tok != "HIERARCHY":
        raise InputError(tokens.path, f"line {line}: not a BVH file (expected 'HIERARCHY', found {tok!r})")
    tok, line = tokens.next("'ROOT'")
    if tok != "ROOT":
        raise InputError(tokens.path, f"line {line}: expected 'ROOT', found {tok!r}")

    def parse_joint(parent, is_end=False):
        if is_end:
            line = tokens.expect("{")
            tokens.expect("OFFSET")
            off = [tokens.number("End Site offset") for _ in range(3)]
            end_parents.append(parent)
            end_offsets.append(off)
            tokens.expect("}")
            return
        name, line = tokens.next("a joint name")
        if name in ("{", "}"):
            raise InputError(tokens.path, f"line {line}: joint has no name")
        if name in names:
            raise InputError(tokens.path, f"line {line}: joint name {name!r} appears twice")
        j = len(names)
        names.append(name)
        parents.append(parent)
        tokens.expect("{")
        tokens.expect("OFFSET")
        offsets.append([tokens.number(f"OFFSET of {name}") for _ in range(3)])
        chans = ()
        if tokens.peek() == "CHANNELS":
            tokens.next()
            count_tok, count_line = tokens.next("channel count")
            if not count_tok.isdigit():
                raise InputError(tokens.path, f"line {count_line}: channel count is not a whole number ({count_tok!r})")
            chans = []
            for _ in range(int(count_tok)):
                ch, ch_line = tokens.next("a channel name")
                if ch not in _KNOWN_CHANNELS:
                    raise InputError(tokens.path, f"line {ch_line}: unknown channel {ch!r} of {name} "
                                                  f"(CHANNELS says {count_tok})")
                chans.append(ch)
            chans = tuple(chans)
        channels.append(chans)
        while True:
            tok, line = tokens.next(f"'}}' closing {name}")
            if tok == "}":
                return
            if tok == "JOINT":
                parse_joint(j)
            elif tok.lower() == "end":
                site, site_line = tokens.next("'Site'")
                if site.lower() != "site":
                    raise InputError(tokens.path, f"line {site_line}: expected 'Site', found {site!r}")
                parse_joint(j, is_end=True)
            else:
                raise InputError(tokens.path, f"line {line}: unexpected {tok!r} inside joint {name}")

    parse_joint(-1)
    return names, parents, offsets, channels, end_parents, end_offsets


def read_bvh(path, units=None, joint_map=None) -> BvhMotion:
    """Read a BVH file.

    Parameters
    ----------
    path : str or os.PathLike
    units : float or str or None
        Metres per file unit, or a name in :data:`UNIT_NAMES` (``"cmu"``, ``"m"``,
        ``"cm"``, ``"mm"``, ``"inch"``); ``None`` infers it from the skeleton's size
        (see ``motion.units_source``).
    joint_map : dict or str or os.PathLike or None
        ``{our joint name: file joint name}`` for joints the names and structure do not
        reveal (see :mod:`depthtrack.io.bvh.names`), or a JSON file holding it. Kept
        on the motion: every use of its contract joints (synth, swim, retargeting,
        the motion prior) goes through it.

    Returns
    -------
    BvhMotion

    Raises
    ------
    InputError
        Unreadable or malformed file (with the line number), a frame count that
        disagrees with the ``Frames:`` header, non-finite values, a joint map that
        names joints the file does not have.
    """
    path = os.fspath(path)
    try:
        text = Path(path).read_text(encoding="utf-8", errors="replace")
    except OSError as exc:
        raise InputError(path, f"cannot read BVH file ({exc.strerror or exc})") from None
    lines = text.splitlines()
    motion_line = next((i for i, l in enumerate(lines) if l.strip() == "MOTION"), None)
    if motion_line is None:
        if not text.strip():
            raise InputError(path, "empty BVH file")
        if not text.lstrip().startswith("HIERARCHY"):
            raise InputError(path, "line 1: not a BVH file (expected 'HIERARCHY')")
        raise InputError(path, f"line {len(lines)}: no MOTION section")

    tokens = _Tokens(lines[:motion_line], path)
    names, parents, offsets, channels, end_parents, end_offsets = _parse_hierarchy(tokens)
    if tokens.peek() is not None:
        tok, line = tokens.next()
        raise InputError(path, f"line {line}: unexpected {tok!r} after the hierarchy "
                               f"(more than one ROOT?)")

    # Header lines "Frames: N" and "Frame Time: t".
    def header(index, label):
        if index >= len(lines):
            raise InputError(path, f"line {index + 1}: file ends where '{label}' was expected")
        line = lines[index].strip()
        match = re.fullmatch(rf"{label}\s*(\S+)", line)
        if not match:
            raise InputError(path, f"line {index + 1}: expected '{label} ...', found {line[:40]!r}")
        return match.group(1)

    frames_text = header(motion_line + 1, "Frames:")
    if not frames_text.isdigit():
        raise InputError(path, f"line {motion_line + 2}: frame count is not a whole number ({frames_text!r})")
    n_frames = int(frames_text)
    time_text = header(motion_line + 2, "Frame Time:")
    try:
        frame_time = float(time_text)
    except ValueError:
        raise InputError(path, f"line {motion_line + 3}: frame time is not a number ({time_text!r})") from None
    if not (math.isfinite(frame_time) and frame_time > 0):
        raise InputError(path, f"line {motion_line + 3}: frame time must be positive, not {time_text}")

    n_channels = sum(len(c) for c in channels)
    first = motion_line + 3
    body = lines[first:]
    while body and not body[-1].strip():
        body.pop()
    counts = np.fromiter((len(l.split()) for l in body), dtype=int, count=len(body))
    bad = np.flatnonzero(counts != n_channels)
    if len(bad):
        i = int(bad[0])
        raise InputError(path, f"line {first + i + 1}: motion line has {counts[i]} values, "
                               f"the hierarchy has {n_channels} channels")
    if len(body) != n_frames:
        raise InputError(path, f"frame count mismatch: header says {n_frames} frames, "
                               f"the file has {len(body)} motion lines")
    if n_frames == 0:
        raise InputError(path, "BVH file has no frames")
    try:
        values = np.array(" ".join(body).split(), dtype=float)
    except ValueError:
        for i, l in enumerate(body):
            try:
                np.array(l.split(), dtype=float)
            except ValueError:
                raise InputError(path, f"line {first + i + 1}: motion line holds a value that is "
                                       f"not a number") from None
        raise
    frames = values.reshape(n_frames, n_channels)
    if not np.all(np.isfinite(frames)):
        i = int(np.flatnonzero(~np.all(np.isfinite(frames), axis=1))[0])
        raise InputError(path, f"line {first + i + 1}: motion line holds a non-finite value")

    offsets_u = np.asarray(offsets, float).reshape(-1, 3)
    end_offsets_u = np.asarray(end_offsets, float).reshape(-1, 3)
    parents_a = np.asarray(parents, dtype=int)
    if joint_map is not None:
        joint_map = check_joint_map(joint_map) if isinstance(joint_map, dict) else read_joint_map(joint_map)
        known = set(names) | {strip_namespace(n) for n in names}
        absent = sorted(f"{ours} -> {theirs}" for ours, theirs in joint_map.items() if theirs not in known)
        if absent:
            raise InputError(path, f"the joint map names joints the file does not have ({', '.join(absent)}); "
                                   f"its joints: {' '.join(names)}")
    if units is None:
        rest = np.zeros_like(offsets_u)
        for j, p in enumerate(parents_a):
            rest[j] = offsets_u[j] + (rest[p] if p >= 0 else 0.0)
        ends = rest[np.asarray(end_parents, int)] + end_offsets_u if end_parents else np.zeros((0, 3))
        try:
            units_m, source = infer_units(rest, ends, names, parents_a, end_parents, joint_map)
        except InputError as exc:
            raise InputError(path, exc.problem) from None
    else:
        units_m, source = resolve_units(units, path)

    starts = np.cumsum([0] + [len(c) for c in channels])[:-1].astype(int)
    return BvhMotion(
        joint_names=list(names),
        parents=parents_a,
        offsets=offsets_u * units_m,
        channels=list(channels),
        channel_start=starts,
        frame_time=frame_time,
        frames=frames,
        end_site_parents=np.asarray(end_parents, dtype=int),
        end_site_offsets=end_offsets_u * units_m,
        units_m=units_m,
        units_source=source,
        path=path,
        joint_map=joint_map,
    )


