"""Where a fit leaves the person unexplained (``evaluate.fit.unexplained_parts``), the true
poses of a synthetic sequence rebuilt (``synth.generate.rendered_poses``), and
tools/unexplained_where.py that puts them together."""
import json

import numpy as np
import pytest

from depthtrack.errors import InputError
from depthtrack.evaluate.fit import frame_fit, unexplained_parts
from tool_module import load_tool


def test_the_parts_in_closed_form():
    """A body one pixel right of its person, a blob of the person it does not reach, and a
    patch it covers 0.5 m off: each lands in its part, and the parts add up to
    ``frame_fit``'s unexplained share."""
    person = np.zeros((40, 60), bool)
    person[10:30, 10:30] = True                 # 400 pixels
    person[5:8, 50:53] = True                   # a 3 x 3 blob far from the body
    depth = np.where(person, 2.0, 0.0)
    rendered = np.zeros_like(depth)
    rendered[10:30, 11:31] = 2.0                # one pixel right
    rendered[18:21, 18:21] = 2.5                # 3 x 3 covered 0.5 m off, deep inside
    counts = unexplained_parts(person, depth, rendered, band=2)
    reading, near, away, off_near, off_away, extra = counts
    assert reading == 409
    assert near == 20 and away == 9             # the left column; the blob
    assert off_near == 0 and off_away == 9
    assert extra == 20                          # the body's column right of the person
    _, unexplained, _ = frame_fit(person, depth, rendered)
    assert (near + away + off_near + off_away) / reading == pytest.approx(unexplained)


@pytest.fixture(scope="module")
def shaped(tmp_path_factory):
    """Five frames of the built-in wave by a random person (seed 4), SR4000, ToF noise."""
    from depthtrack.io import open_sequence
    from depthtrack.synth.generate import synthesize_procedural
    from depthtrack.synth.subject import make_subject

    body, subject = make_subject(None, "random", 4, "none")
    d = tmp_path_factory.mktemp("shaped") / "seq"
    synthesize_procedural("wave", d, start=0.8, seconds=0.2, seed=2, body=body, subject=subject,
                          height=body.height)
    return d, open_sequence(d)


def test_the_true_poses_are_rebuilt_from_sequence_json(shaped):
    from depthtrack.synth.generate import rendered_poses

    d, seq = shaped
    meta = json.loads((d / "sequence.json").read_text())
    body, poses = rendered_poses(meta)
    assert poses.shape == (len(seq), 48)
    assert body.height == pytest.approx(meta["synth"]["shape"]["height_m"], abs=1e-4)
    joints = np.asarray(body.joint_positions(poses))
    assert np.abs(joints - seq.joints).max() < 1e-5      # joints.csv keeps micrometres
    with pytest.raises(InputError, match="not a synthetic sequence"):
        rendered_poses({"fps": 25.0})


def test_the_tool_scores_a_track_at_the_true_poses_as_the_truth(shaped, tmp_path, capsys):
    """A "track" holding the true body and poses: its row is the truth's, and the truth
    explains all but a sliver of the person (the noise's flying pixels)."""
    from depthtrack.body.skeleton import POSE_NAMES
    from depthtrack.io import write_track
    from depthtrack.synth.generate import rendered_poses

    d, seq = shaped
    body, poses = rendered_poses(json.loads((d / "sequence.json").read_text()))
    track = write_track(tmp_path / "track", np.asarray(body.joint_positions(poses)), poses,
                        POSE_NAMES, body, seq.fps)
    (track / "body.json").write_text(body.to_json())
    tool = load_tool("unexplained_where")
    assert tool.main([str(d), str(track), "--json", str(tmp_path / "parts.json")]) == 0
    shares = json.loads((tmp_path / "parts.json").read_text())["shares"]
    assert shares["track's body, track's poses"] == shares["true body, true poses"]
    assert shares["true body, true poses"]["unexplained"] < 0.03
    assert shares["true body, true poses"]["silhouette_iou"] > 0.85
    capsys.readouterr()
    assert tool.main([str(tmp_path / "nope"), str(track)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "nope" in err
