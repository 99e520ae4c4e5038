"""TUM RGB-D benchmark folders: ``depth.txt`` + ``depth/*.png``.

``depth.txt`` lists ``timestamp filename`` per frame (``#`` lines are comments); each PNG
is 16-bit single channel, 5000 units per metre (``depth_units`` 0.0002 m), 0 = no reading.
The folder carries no intrinsics: give ``intrinsics`` ("fx,fy,cx,cy" or a preset:
``freiburg1``, ``freiburg2``, ``freiburg3``, ``tum-ros-default``, or one of our camera
presets of the same size); without it, a folder named like the benchmark's
(``rgbd_dataset_freiburg2_xyz``) gets that Kinect's published intrinsics, recorded in
``meta["source"]["intrinsics_from"]``.
"""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from ..errors import InputError
from .arrays import RecordingSequence
from .registry import Reader, fps_from_timestamps, parse_intrinsics
from .validation import finite_positive as positive
from .sequence import _read_png16, png_header

#: Metres per unit of the benchmark's depth PNGs (5000 units per metre).
TUM_DEPTH_UNITS = 1.0 / 5000.0
_FREIBURG = re.compile(r"freiburg([123])", re.IGNORECASE)


class TumSequence(RecordingSequence):
    """A TUM RGB-D folder's depth frames (listed in ``depth.txt``, read lazily)."""

    def __init__(self, path, files, timestamps, camera, fps, depth_scale, meta):
        super().__init__(path, camera, fps, depth_scale, timestamps, meta)
        self._files = files

    def _read(self, start, stop):
        frames = []
        for f in self._files[start:stop]:
            raw = _read_png16(f)
            if raw.shape != self.camera.shape:
                raise InputError(f, f"frame is {raw.shape[1]} x {raw.shape[0]}, the first frame is "
                                    f"{self.camera.width} x {self.camera.height}")
            frames.append(raw)
        return frames


def read_depth_list(path: Path):
    """``(timestamps (F,) float, files [F paths])`` from a TUM ``depth.txt``."""
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(path, f"cannot read ({getattr(exc, 'strerror', None) or exc})") from None
    times, files = [], []
    for number, line in enumerate(lines, start=1):
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        fields = line.split()
        if len(fields) < 2:
            raise InputError(path, f"line {number}: expected 'timestamp filename'")
        try:
            t = float(fields[0])
        except ValueError:
            raise InputError(path, f"line {number}: timestamp {fields[0]!r} is not a number") from None
        times.append(t)
        files.append(path.parent / fields[1])
    if not files:
        raise InputError(path, "empty sequence: no depth frames listed")
    times = np.asarray(times)
    if np.any(np.diff(times) <= 0):
        k = int(np.flatnonzero(np.diff(times) <= 0)[0]) + 1
        raise InputError(path, f"timestamps do not increase at frame {k}")
    return times, files


def open_tum(path, intrinsics=None, depth_units=None, fps=None) -> TumSequence:
    """Open a TUM RGB-D folder (see the module docstring for the options)."""
    path = Path(path)
    times, files = read_depth_list(path / "depth.txt")
    for f in files:
        if not f.is_file():
            raise InputError(f, "listed in depth.txt but missing")
        width, height, bit_depth, colour = png_header(f)
        if bit_depth != 16 or colour != 0:
            raise InputError(f, f"PNG is not 16-bit single channel (bit depth {bit_depth}, colour type {colour})")
    width, height, _, _ = png_header(files[0])
    source = {"format": "tum-rgbd", "input": str(path)}
    if intrinsics is None:
        match = _FREIBURG.search(path.resolve().name)
        if not match:
            raise InputError(path, "a TUM RGB-D folder has no intrinsics: give --intrinsics fx,fy,cx,cy "
                                   "or a preset (freiburg1, freiburg2, freiburg3, tum-ros-default)")
        intrinsics = f"freiburg{match.group(1)}"
        source["intrinsics_from"] = f"folder name ({intrinsics})"
    camera = parse_intrinsics(intrinsics, width, height, path)
    scale = TUM_DEPTH_UNITS if depth_units is None else positive(depth_units, "depth units", path)
    rate = positive(fps, "fps", path) if fps is not None else fps_from_timestamps(times, 30.0)
    t = times - times[0]
    source["start_time"] = float(times[0])
    return TumSequence(path, files, t, camera, rate, scale, {"source": source})


def _is_tum(path, head) -> bool:
    return path.is_dir() and (path / "depth.txt").is_file() and (path / "depth").is_dir()


READERS = {
    "tum-rgbd": Reader("tum-rgbd", open_tum, sniff=_is_tum,
                       options=("intrinsics", "depth_units", "fps"),
                       description="TUM RGB-D folder (depth.txt + depth/*.png, 5000 units/m)"),
}
