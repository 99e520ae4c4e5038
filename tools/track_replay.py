"""What the diagnostics that replay one frame of a kept track share (``replay_search``,
``heading_tiles``): the sequence, the track's body and poses read with one-line errors, and
a tracker put on a frame the way the track reached it."""
from __future__ import annotations

import argparse
import pathlib
import sys

REPO = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))
import depthtrack  # noqa: E402,F401  (before numpy: the same OpenBLAS kernels on every machine)
import numpy as np  # noqa: E402

from depthtrack.body import BodyModel  # noqa: E402
from depthtrack.errors import InputError  # noqa: E402
from depthtrack.io import open_sequence  # noqa: E402


def read_track(seq_dir: pathlib.Path, track_dir: pathlib.Path, frames):
    """``(sequence, body, poses (F, 48))`` of a synthesized sequence with ground truth and a
    track of it (``body.json``, ``poses.npz``); raises :class:`InputError` (or ``OSError``,
    ``KeyError``) naming the file when one is missing or a frame is not in ``1..F-1``."""
    seq = open_sequence(seq_dir)
    body = BodyModel.from_json(track_dir / "body.json")
    poses = np.load(track_dir / "poses.npz")["poses"]
    if not all(1 <= f < len(poses) for f in frames):
        raise InputError(track_dir / "poses.npz", f"frames must be 1..{len(poses) - 1}")
    if seq.joints is None:
        raise InputError(seq_dir, "no ground-truth joints (groundtruth/joints.csv)")
    return seq, body, poses


def parse_frames(text: str) -> list:
    """``"F,F,..."`` as a list of ints; raises :class:`InputError` saying what it wanted."""
    try:
        return [int(f) for f in text.split(",")]
    except ValueError:
        raise InputError(None, f"frames must be comma-separated integers, not {text!r}") from None


def frame_energy(tracker, seq, poses, f: int):
    """``(frame, energy)``: frame ``f`` observed as the track saw it (started on ``f - 1``'s
    pose, predicted from it) and its energy without the motion prior, on the tracker's tiles."""
    state, _, _ = tracker.start(tracker.state, seq.depth(f - 1), pose=poses[f - 1])
    frame, _ = tracker._observe(state, seq.depth(f), predicted=poses[f - 1])
    return frame, tracker._energy(frame).without_prior()


def track_parser(doc: str, example: str) -> argparse.ArgumentParser:
    """The command line's parser with its two first arguments, ``seq`` and ``track``; its
    description is the first paragraph of ``doc``, its epilog ``example``."""
    parser = argparse.ArgumentParser(description=doc.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter,
                                     epilog=f"example:\n  {example}")
    parser.add_argument("seq", type=pathlib.Path, help="sequence directory with ground truth")
    parser.add_argument("track", type=pathlib.Path, help="track directory (body.json, poses.npz)")
    return parser
