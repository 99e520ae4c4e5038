"""tools/make_limb_poses.py: the limb library from the train clips only, reproducibly."""
from pathlib import Path

import numpy as np
import pytest

from depthtrack.body import BodyModel
from depthtrack.track.reseat import LIMB_SLOTS, MIRROR, library_path
from tool_module import load_tool

REPO = Path(__file__).resolve().parents[1]
DATA = REPO.parent / "shared" / "data"


def _tool():
    return load_tool("make_limb_poses")


def test_spread_picks_the_farthest_points_first():
    points = np.array([[0.0], [0.1], [1.0], [0.5], [0.9]])
    assert _tool().spread(points, 3).tolist() == [0, 2, 3]       # 0, then 1.0, then 0.5


def test_right_limbs_are_mirrored_onto_the_left_ones():
    tool = _tool()
    left = np.array([0.3, 0.2, -0.1, -1.0, 0.1, 0.2])
    pose = np.zeros((1, 48))
    pose[0, LIMB_SLOTS["l_arm"]] = left
    pose[0, LIMB_SLOTS["r_arm"]] = left * MIRROR
    arms = tool.limb_samples(pose)["arm"]
    np.testing.assert_allclose(arms[0], arms[1])
    # and a mirrored pair of arms puts the wrists at mirrored places
    joints = np.asarray(BodyModel.default(1.75).joint_positions(pose[0]))
    from depthtrack.contract import JOINT_INDEX as J
    lw, rw = joints[J["l_wrist"]], joints[J["r_wrist"]]
    pelvis = joints[J["pelvis"]]
    np.testing.assert_allclose(lw[1:], rw[1:], atol=1e-6)
    assert abs((lw[0] - pelvis[0]) + (rw[0] - pelvis[0])) < 1e-6


def test_missing_train_clips_are_refused(tmp_path, capsys):
    out = tmp_path / "limbs.npz"
    assert _tool().main(["--data", str(tmp_path), "-o", str(out)]) == 2
    assert "train clips not found" in capsys.readouterr().err
    assert not out.exists()


@pytest.mark.skipif(not (DATA / "cmu-extra").is_dir(), reason="needs ../shared/data")
def test_the_shipped_library_is_what_the_tool_makes(tmp_path):
    out = tmp_path / "limbs.npz"
    assert _tool().main(["--data", str(DATA), "-o", str(out)]) == 0
    # the same arrays; not the same bytes: another numpy build may round the last bit of a
    # sum differently (a fresh machine's numpy 2.4 differed by 1e-16 from the shipped file)
    made, shipped = np.load(out), np.load(library_path())
    assert made.files == shipped.files
    for key in made.files:
        if made[key].dtype.kind == "f":
            np.testing.assert_allclose(made[key], shipped[key], rtol=0, atol=1e-12)
        else:
            assert np.array_equal(made[key], shipped[key]), key
