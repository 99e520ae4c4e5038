"""The tracker's behaviour is pinned: the same joints (within 1 mm) as the tracker before
its refactor into stages, on a short synthetic sequence.

``tests/data/tracker_reference.npz`` was written by the tracker of commit e58c459 (the
single-module tracker) with::

    PYTHONPATH=$PWD .venv/bin/python tests/test_track_reference.py --write

which runs :func:`_track_both` below: ``synthesize_procedural("mixed", seconds=0.24, seed=3)``
(6 frames, SR4000, ToF noise), then ``run_tracking`` twice: ``hc+ep`` with the front/back
check over 3 frames, and ``hc`` with the pixel likelihood after removing ``subject`` from
``sequence.json`` (the height fit). Changes of behaviour made on purpose since are turned
off here (:data:`LATER_CHANGES_OFF`), so that the pin still holds for everything else.
"""
import json
import sys
from pathlib import Path

import numpy as np
import pytest

REFERENCE = Path(__file__).resolve().parent / "data" / "tracker_reference.npz"
#: The tracker's intended changes since the reference, off: the trunk's twist (6551e11),
#: the heading recheck's judge tile, the final polish of the poses reported (4c788f5), and
#: the re-seat of a limb over free space (2026-11-30).
LATER_CHANGES_OFF = {"energy": {"twist_std": 0.0}, "search": {"untwist": []},
                     "heading": {"judge_tile": 0, "reseat_free": 0.0, "reseat_hidden": 0.0},
                     "polish": {"final_tile": 0}}


def _track_both(tmp):
    from depthtrack.io import open_sequence
    from depthtrack.synth.generate import synthesize_procedural
    from depthtrack.track import TrackerSettings, run_tracking

    seq_dir = Path(tmp) / "seq"
    synthesize_procedural("mixed", seq_dir, seconds=0.24, seed=3)
    a, _, summary_a = run_tracking(open_sequence(seq_dir), method="hc+ep",
                                   settings=TrackerSettings(heading_frames=3).updated(LATER_CHANGES_OFF))
    meta = json.loads((seq_dir / "sequence.json").read_text())
    del meta["subject"]
    (seq_dir / "sequence.json").write_text(json.dumps(meta))
    b, _, summary_b = run_tracking(open_sequence(seq_dir), method="hc", likelihood="pixel",
                                   settings=TrackerSettings(heading_frames=0).updated(LATER_CHANGES_OFF))
    return {"hc_ep_heading": a.joints, "hc_pixel_height_fit": b.joints,
            "body_height_fit": np.array(summary_b["body_height_m"])}, summary_a, summary_b


def test_tracker_reproduces_the_reference_joints(tmp_path):
    from renderer_kind import software_renderer

    if not software_renderer():
        # recorded on llvmpipe: on an H200 the fitted height came out 1.774 against 1.786 m
        pytest.skip("the reference was recorded with Mesa's llvmpipe; another rasteriser "
                    "rounds differently")
    ref = np.load(REFERENCE)
    got, summary_a, summary_b = _track_both(tmp_path)
    assert summary_a["initialisation_details"]["heading_check"]["frames"] == 3
    assert "fitted" in summary_b["body_height_source"]
    assert float(got["body_height_fit"]) == float(ref["body_height_fit"])
    for key in ("hc_ep_heading", "hc_pixel_height_fit"):
        assert got[key].shape == ref[key].shape == (6, 15, 3)
        assert np.isfinite(ref[key]).all()
        assert np.abs(got[key] - ref[key]).max() < 1e-3, key


if __name__ == "__main__" and "--write" in sys.argv:
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        arrays, _, _ = _track_both(tmp)
    REFERENCE.parent.mkdir(exist_ok=True)
    np.savez_compressed(REFERENCE, **{k: np.asarray(v, np.float64) for k, v in arrays.items()})
    print(f"wrote {REFERENCE}")
