"""Write any opened depth recording as our sequence (directory or ``.npz``), atomically."""
from __future__ import annotations

import json

import numpy as np

from ..errors import InputError
from .sequence import write_sequence

# Keys of sequence.json that write_sequence sets itself.
_CONTRACT_KEYS = ("format", "fps", "depth_scale", "camera", "subject", "marker_names")


def _jsonable(value):
    try:
        json.dumps(value)
        return value
    except (TypeError, ValueError):
        return str(value)


def convert_sequence(seq, out, options=None, progress=None):
    """Write ``seq`` (any :class:`~depthtrack.io.registry.DepthSequence`) to ``out``.

    Frames keep the recording's raw units (``seq.depth_scale``), so 16-bit recordings
    convert without loss; float depth is quantised to ``depth_scale`` (1 mm by default).
    ``sequence.json`` gains a ``source`` block: what the reader knew, the options it was
    opened with and the per-frame ``timestamps`` (seconds).

    Parameters
    ----------
    seq : DepthSequence
    out : path-like
        Directory, or a file ending in ``.npz``.
    options : dict or None
        The reader options used (recorded).
    progress : Progress or None
        Updated once per frame.

    Returns
    -------
    pathlib.Path
    """
    meta = dict(getattr(seq, "meta", None) or {})
    extra = {k: v for k, v in meta.items() if k not in _CONTRACT_KEYS and k not in ("source", "reader")}
    source = dict(meta.get("source") or {}) if isinstance(meta.get("source"), dict) else {}
    source["reader"] = getattr(seq, "reader", None) or source.get("reader")
    source.setdefault("input", str(seq.path))
    if options:
        source["options"] = {k: _jsonable(v) for k, v in options.items()}
    source["timestamps"] = [round(float(t), 9) for t in np.asarray(seq.timestamps, dtype=float)]
    extra["source"] = {k: _jsonable(v) for k, v in source.items()}

    subject = meta["subject"] if isinstance(meta.get("subject"), dict) else seq.subject_height

    def frames():
        for i in range(len(seq)):
            # raw * scale in float64 round-trips exactly through write_sequence's quantiser.
            yield seq.raw_depth(i).astype(np.float64) * seq.depth_scale
            if progress is not None:
                progress.update()

    try:
        return write_sequence(out, frames(), seq.camera, seq.fps, depth_scale=seq.depth_scale,
                              joints=seq.joints, markers=seq.markers, marker_names=seq.marker_names,
                              subject=subject, extra=extra)
    except ValueError as exc:
        if isinstance(exc, InputError):
            raise
        raise InputError(seq.path, f"cannot convert: {exc}") from None


__all__ = ["convert_sequence"]
