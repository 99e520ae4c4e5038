"""Which reader opens a recording: the registry, and the interface every reader returns.

Each format module (``sequence``, ``mkv``, ``rosbag``, ``tum``) ends with ``READERS``, a
small dict of name -> :class:`Reader` (suffixes it claims, a content sniffer, the
function that opens it); this module merges them, adds readers other packages declare
under the entry-point group ``depthtrack.readers``, and :func:`open_sequence` opens any
path through them::

    # another package's pyproject.toml
    [project.entry-points."depthtrack.readers"]
    myformat = "mypackage.depth:READER"      # a Reader, a list/dict of them, or a function returning one

A reader is chosen by, in order: the ``reader=`` option (its name); the path's suffix,
when that reader's sniffer (if it has one) accepts the content; the first reader whose
sniffer accepts the content. Readers added later (plugins, :func:`register_reader`) are
asked before the built-in ones.

Options every reader takes (applied after opening when the reader does not handle them
itself): ``intrinsics`` ("fx,fy,cx,cy" or a preset name, replaces the camera),
``depth_units`` (metres per raw 16-bit unit), ``fps``.
"""
from __future__ import annotations

import importlib.metadata
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Optional, Protocol, runtime_checkable

import numpy as np

from ..camera import Camera
from ..errors import InputError
from .validation import finite_positive

#: The entry-point group other packages add readers through.
ENTRY_POINT_GROUP = "depthtrack.readers"
#: Options :func:`open_sequence` applies to any reader's result.
COMMON_OPTIONS = ("intrinsics", "depth_units", "fps")
#: Bytes of a file's head handed to sniffers.
HEAD_BYTES = 64


@runtime_checkable
class DepthSequence(Protocol):
    """What the tracker, ``eval`` and ``convert`` rely on in an opened recording.

    Attributes
    ----------
    path : pathlib.Path
        What was opened (names outputs and error messages).
    camera : Camera
        Pinhole intrinsics of the frames as :meth:`depth` returns them.
    fps : float
        Frames per second (nominal; see ``timestamps`` for the measured times).
    depth_scale : float
        Metres per unit of :meth:`raw_depth` (what ``convert`` writes into PNGs).
    subject_height : float or None
        Metres, when the recording knows it.
    meta : dict
        Everything else the reader knows (source format, device, topic, ...).
    timestamps : (F,) float
        Seconds of each frame, increasing (the recording's clock; origin reader-defined).
    joints : (F, 15, 3) float or None
        Ground-truth joints (NaN = unknown), ``markers`` (F, M, 3) and ``marker_names``
        (M,) likewise, or None.
    """

    path: Path
    camera: Camera
    fps: float
    depth_scale: float
    subject_height: Optional[float]
    meta: dict

    def __len__(self) -> int: ...

    def depth(self, i: int) -> np.ndarray:
        """(H, W) float32 camera-frame z of frame ``i`` in metres, 0 = no reading."""

    def raw_depth(self, i: int) -> np.ndarray:
        """(H, W) uint16 frame ``i`` in units of ``depth_scale``."""

    @property
    def timestamps(self) -> np.ndarray: ...

    @property
    def joints(self): ...

    @property
    def markers(self): ...

    @property
    def marker_names(self): ...


@dataclass(frozen=True)
class Reader:
    """One input format.

    Parameters
    ----------
    name : str
        Unique name (``reader=`` option, messages).
    open : callable(path, **options) -> DepthSequence
        Raises :class:`InputError` for input it cannot read.
    suffixes : tuple of str
        Lower-case file suffixes it claims (``".mkv"``); none for directories.
    sniff : callable(path, head: bytes) -> bool, or None
        True when the content is this format; ``head`` is the file's first
        :data:`HEAD_BYTES` bytes (``b""`` for a directory). Must not raise.
    options : tuple of str
        Option names ``open`` takes besides the path (beyond :data:`COMMON_OPTIONS`,
        which are applied generically unless listed here).
    description : str
        One line for messages and documentation.
    """

    name: str
    open: Callable[..., Any]
    suffixes: tuple = ()
    sniff: Optional[Callable[[Path, bytes], bool]] = None
    options: tuple = ()
    description: str = ""


_READERS: dict = {}          # name -> Reader, registration order (plugins appended)
_BUILTINS_LOADED = False
_PLUGINS_LOADED = False


def register_reader(reader: Reader) -> Reader:
    """Add (or replace, by name) a reader; it is asked before the ones registered earlier."""
    if not isinstance(reader, Reader):
        raise TypeError(f"register_reader wants a Reader, not {type(reader).__name__}")
    _READERS.pop(reader.name, None)
    _READERS[reader.name] = reader
    return reader


def unregister_reader(name: str) -> None:
    """Remove a reader by name (no error when absent)."""
    _READERS.pop(name, None)


def _load_builtins() -> None:
    global _BUILTINS_LOADED
    if _BUILTINS_LOADED:
        return
    _BUILTINS_LOADED = True
    from . import mkv, rosbag, sequence_readers, tum

    builtin = {}
    # Registration order; the last is asked first: our own directory and .npz.
    for module in (mkv, rosbag, tum, sequence_readers):
        builtin.update(module.READERS)
    # Built-ins go first in the order, so that anything registered already (or later) wins.
    others = dict(_READERS)
    _READERS.clear()
    _READERS.update(builtin)
    for reader in others.values():
        register_reader(reader)


def _readers_from(obj, origin: str) -> list:
    if callable(obj) and not isinstance(obj, Reader):
        obj = obj()
    if isinstance(obj, Reader):
        return [obj]
    if isinstance(obj, dict):
        obj = list(obj.values())
    if isinstance(obj, (list, tuple)) and all(isinstance(r, Reader) for r in obj):
        return list(obj)
    raise TypeError(f"{origin} gave {type(obj).__name__}, not a Reader or a list/dict of them")


def load_plugins(force: bool = False) -> list:
    """Register the readers declared under :data:`ENTRY_POINT_GROUP`; returns their names.

    A plugin that fails to load is skipped with a warning (our own formats keep working).
    Built-in readers listed there by our own package are the same objects and change nothing.
    """
    global _PLUGINS_LOADED
    if _PLUGINS_LOADED and not force:
        return []
    _PLUGINS_LOADED = True
    _load_builtins()
    names = []
    for ep in importlib.metadata.entry_points(group=ENTRY_POINT_GROUP):
        try:
            readers = _readers_from(ep.load(), f"entry point {ep.name} = {ep.value}")
        except Exception as exc:  # a broken plugin must not stop the rest
            warnings.warn(f"depthtrack: skipping reader plugin {ep.name!r}: {exc}", stacklevel=2)
            continue
        for reader in readers:
            if _READERS.get(reader.name) is not reader:
                register_reader(reader)
            names.append(reader.name)
    return names


def readers() -> list:
    """All registered readers, in the order they are asked (latest first)."""
    load_plugins()
    return list(reversed(_READERS.values()))


def _head(path: Path) -> bytes:
    if path.is_dir():
        return b""
    try:
        with open(path, "rb") as f:
            return f.read(HEAD_BYTES)
    except OSError as exc:
        raise InputError(path, f"cannot read ({exc.strerror or exc})") from None


def _sniffs(reader: Reader, path: Path, head: bytes) -> bool:
    try:
        return bool(reader.sniff(path, head))
    except Exception:  # a sniffer that raises means "not mine"
        return False


def choose_reader(path, reader: Optional[str] = None) -> Reader:
    """The reader for ``path``: by name, else by suffix (content permitting), else by content.

    Raises
    ------
    InputError
        No such path, unknown reader name, or no reader recognises it.
    """
    path = Path(path)
    known = readers()
    if reader is not None:
        for r in known:
            if r.name == reader:
                break
        else:
            raise InputError(None, f"unknown reader {reader!r}; known: {', '.join(r.name for r in known)}")
    if not path.exists():
        raise InputError(path, "no such file or directory")
    if reader is not None:
        return r
    head = _head(path)
    suffix = path.suffix.lower()
    if suffix and not path.is_dir():
        for r in known:
            if suffix in r.suffixes and (r.sniff is None or _sniffs(r, path, head)):
                return r
    for r in known:
        if r.sniff is not None and _sniffs(r, path, head):
            return r
    if path.is_dir() and "depthtrack-directory" in _READERS:
        # Our own directory reader says precisely what is missing (sequence.json, depth/).
        return _READERS["depthtrack-directory"]
    what = "directory" if path.is_dir() else "file"
    raise InputError(path, f"not a readable depth recording ({what}; readers tried: "
                           f"{', '.join(r.name for r in reversed(known))})")


def open_sequence(path, **options):
    """Open any readable depth recording (directory, ``.npz``, ``.mkv``, bag, TUM folder, ...).

    Parameters
    ----------
    path : path-like
    reader : str, optional
        Force a reader by name (see :func:`readers`).
    intrinsics : str or (4,) float, optional
        ``"fx,fy,cx,cy"`` or a preset name (``freiburg1``, ``sr4000``, ...): replaces the
        recorded camera (the frame size stays the recording's).
    depth_units : float, optional
        Metres per raw 16-bit unit, replacing the recorded or default units.
    fps : float, optional
        Frames per second, replacing the recorded or measured rate.
    **options
        Reader-specific (e.g. ``topic`` for ROS bags); ``None`` values are ignored.

    Returns
    -------
    DepthSequence

    Raises
    ------
    InputError
        One line naming the file and why it cannot be read.
    """
    options = {k: v for k, v in options.items() if v is not None}
    chosen = choose_reader(path, options.pop("reader", None))
    unknown = [k for k in options if k not in chosen.options and k not in COMMON_OPTIONS]
    if unknown:
        raise InputError(path, f"option {', '.join(sorted(unknown))} does not apply to "
                               f"{chosen.name} input")
    own = {k: v for k, v in options.items() if k in chosen.options}
    seq = chosen.open(Path(path), **own)
    common = {k: v for k, v in options.items() if k in COMMON_OPTIONS and k not in chosen.options}
    if "intrinsics" in common:
        seq.camera = parse_intrinsics(common["intrinsics"], seq.camera.width, seq.camera.height, path)
    if "depth_units" in common:
        seq.depth_scale = finite_positive(common["depth_units"], "depth units", path)
    if "fps" in common:
        seq.fps = finite_positive(common["fps"], "fps", path)
    try:
        seq.reader = chosen.name      # which reader opened it (convert records it)
    except AttributeError:
        pass
    return seq


# ------------------------------------------------------------------ shared option parsing
#: Published intrinsics of the TUM RGB-D benchmark's Kinects (640 x 480 depth), and the
#: default the benchmark gives for its ROS-registered data.
TUM_PRESETS = {
    "freiburg1": (517.3, 516.5, 318.6, 255.3),
    "freiburg2": (520.9, 521.0, 325.1, 249.7),
    "freiburg3": (535.4, 539.2, 320.1, 247.6),
    "tum-ros-default": (525.0, 525.0, 319.5, 239.5),
}


def parse_intrinsics(spec, width: int, height: int, path=None) -> Camera:
    """A camera of ``width x height`` from ``"fx,fy,cx,cy"``, four numbers or a preset name.

    Presets: :data:`TUM_PRESETS` (any frame size) and ``depthtrack.camera.CAMERA_PRESETS``
    (only at their own frame size).
    """
    from ..camera import CAMERA_PRESETS

    if isinstance(spec, str) and spec.strip().lower() in TUM_PRESETS:
        values = TUM_PRESETS[spec.strip().lower()]
    elif isinstance(spec, str) and spec.strip().lower() in CAMERA_PRESETS:
        preset = CAMERA_PRESETS[spec.strip().lower()]
        if (preset["width"], preset["height"]) != (width, height):
            raise InputError(path, f"camera preset {spec!r} is {preset['width']} x {preset['height']}, "
                                   f"the frames are {width} x {height}")
        values = (preset["fx"], preset["fy"], preset["cx"], preset["cy"])
    else:
        parts = spec.split(",") if isinstance(spec, str) else list(spec)
        presets = ", ".join(list(TUM_PRESETS) + list(CAMERA_PRESETS))
        if len(parts) != 4:
            raise InputError(path, f"intrinsics {spec!r} are neither fx,fy,cx,cy nor a preset ({presets})")
        try:
            values = tuple(float(p) for p in parts)
        except (TypeError, ValueError):
            raise InputError(path, f"intrinsics {spec!r} are neither fx,fy,cx,cy nor a preset "
                                   f"({presets})") from None
    try:
        return Camera(width=width, height=height, fx=values[0], fy=values[1], cx=values[2], cy=values[3])
    except InputError as exc:
        raise InputError(path, exc.problem) from None


def fps_from_timestamps(timestamps, default: float) -> float:
    """Frame rate from the median frame interval, or ``default`` with fewer than 2 frames."""
    t = np.asarray(timestamps, dtype=float)
    if t.size >= 2:
        dt = np.median(np.diff(t))
        if np.isfinite(dt) and dt > 0:
            return float(1.0 / dt)
    return float(default)


__all__ = ["DepthSequence", "Reader", "ENTRY_POINT_GROUP", "register_reader", "unregister_reader",
           "load_plugins", "readers", "choose_reader", "open_sequence", "parse_intrinsics",
           "TUM_PRESETS", "fps_from_timestamps"]
