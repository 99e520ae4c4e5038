"""BVH reading: real CMU and DeepMimic files, units, contract joints, malformed input."""
from pathlib import Path

import numpy as np
import pytest

from depthtrack.contract import JOINT_INDEX
from depthtrack.errors import InputError
from depthtrack.io.bvh import UNIT_NAMES, axis_rotations, matrix_to_euler, read_bvh

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
CMU = DATA / "cmu" / "126_01.bvh"
MOTIONS = sorted((DATA / "motions").glob("*.bvh"))

needs_cmu = pytest.mark.skipif(not CMU.exists(), reason="shared CMU data absent")
needs_motions = pytest.mark.skipif(not MOTIONS, reason="shared motion data absent")

SMALL = """HIERARCHY
ROOT Hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation
  JOINT LeftUpLeg
  {
    OFFSET 10 0 0
    CHANNELS 3 Zrotation Yrotation Xrotation
    End Site
    {
      OFFSET 0 -40 0
    }
  }
}
MOTION
Frames: 2
Frame Time: 0.5
1 2 3 0 0 0 90 0 0
1 2 3 0 90 0 0 0 0
"""


def _header_frames(path):
    for line in Path(path).read_text().splitlines():
        if line.startswith("Frames:"):
            return int(line.split()[1])


@needs_cmu
def test_cmu_units_rate_and_limb_lengths():
    motion = read_bvh(CMU)
    assert motion.n_frames == _header_frames(CMU)
    assert motion.fps == pytest.approx(120.0, rel=1e-4)
    assert motion.units_m == pytest.approx(0.0254 / 0.45)
    assert "inferred" in motion.units_source and "cmu" in motion.units_source
    joints = motion.contract_joint_positions()
    assert joints.shape == (motion.n_frames, 15, 3)
    for side in "lr":
        thigh = np.linalg.norm(joints[:, JOINT_INDEX[f"{side}_knee"]] - joints[:, JOINT_INDEX[f"{side}_hip"]], axis=-1)
        shin = np.linalg.norm(joints[:, JOINT_INDEX[f"{side}_ankle"]] - joints[:, JOINT_INDEX[f"{side}_knee"]], axis=-1)
        assert np.all((thigh > 0.35) & (thigh < 0.5))
        assert np.all((shin > 0.35) & (shin < 0.5))
    # Explicit units agree with the inferred ones, and a different unit scales lengths.
    given = read_bvh(CMU, units="cmu")
    assert given.units_source.startswith("given")
    np.testing.assert_allclose(given.joint_positions()[:5], motion.joint_positions()[:5])
    inch = read_bvh(CMU, units="inch")
    np.testing.assert_allclose(inch.offsets, motion.offsets * 0.45, atol=1e-12)


@needs_motions
@pytest.mark.parametrize("path", MOTIONS, ids=lambda p: p.stem)
def test_deepmimic_motions_in_metres(path):
    motion = read_bvh(path)
    assert motion.units_m == 1.0
    assert motion.n_frames == _header_frames(path)
    joints = motion.contract_joint_positions()
    # Documented skeleton: head centre 0.175 m above Neck1, thigh 0.4215 m, shin 0.4099 m.
    neck = motion.joint_positions()[:, motion.joint_index("Neck1")]
    np.testing.assert_allclose(np.linalg.norm(joints[:, JOINT_INDEX["head"]] - neck, axis=-1), 0.175, atol=1e-6)
    thigh = np.linalg.norm(joints[:, JOINT_INDEX["l_knee"]] - joints[:, JOINT_INDEX["l_hip"]], axis=-1)
    np.testing.assert_allclose(thigh, 0.421546, atol=1e-6)
    # Character faces +x, +z is its right: the right hip has larger z than the left.
    assert np.all(joints[:, JOINT_INDEX["r_hip"], 2] > joints[:, JOINT_INDEX["l_hip"], 2]) or \
        motion.frames[:, 4].std() > 30  # unless the character turns around


def test_small_file_kinematics_closed_form(tmp_path):
    path = tmp_path / "small.bvh"
    path.write_text(SMALL)
    motion = read_bvh(path, units="cm")
    assert motion.units_source.startswith("given")
    np.testing.assert_allclose(motion.root_positions(), [[0.01, 0.02, 0.03]] * 2)
    pos = motion.joint_positions()
    # Frame 0: hip offset (0.1, 0, 0) unrotated; the leg's own Z rotation of 90 deg
    # turns its end site (0, -0.4, 0) to (0.4, 0, 0).
    np.testing.assert_allclose(pos[0, 1], [0.11, 0.02, 0.03], atol=1e-12)
    np.testing.assert_allclose(motion.end_site_positions()[0, 0], [0.51, 0.02, 0.03], atol=1e-12)
    # Frame 1: root Y rotation of 90 deg takes the hip offset (0.1, 0, 0) to (0, 0, -0.1).
    np.testing.assert_allclose(pos[1, 1], [0.01, 0.02, 0.03 - 0.1], atol=1e-12)


def test_euler_round_trip_all_orders():
    rng = np.random.default_rng(1)
    for order in ("ZYX", "XYZ", "YXZ", "ZXY", "XZY", "YZX"):
        angles = rng.uniform(-85, 85, (50, 3))
        R = axis_rotations(order[0], angles[:, 0]) @ axis_rotations(order[1], angles[:, 1]) \
            @ axis_rotations(order[2], angles[:, 2])
        np.testing.assert_allclose(matrix_to_euler(R, order), angles, atol=1e-9)


def test_unit_names():
    assert UNIT_NAMES["cmu"] == pytest.approx(0.056444, rel=1e-4)


@pytest.mark.parametrize("mutate, message", [
    (lambda s: "", "empty"),
    (lambda s: s.replace("HIERARCHY", "HIERARCHX"), "line 1"),
    (lambda s: s.replace("Frames: 2", "Frames: 3"), "frame count mismatch"),
    (lambda s: s.replace("1 2 3 0 90 0 0 0 0", "1 2 3 0 90 0 0 0"), "line 20"),
    (lambda s: s.replace("1 2 3 0 90 0 0 0 0", "1 2 3 0 90 0 0 0 x"), "line 20"),
    (lambda s: s.replace("1 2 3 0 90 0 0 0 0", "1 2 3 0 90 0 0 0 nan"), "non-finite"),
    (lambda s: s.replace("OFFSET 10 0 0", "OFFSET 10 zero 0"), "line 8"),
    (lambda s: s.replace("Zrotation Yrotation Xrotation\n    End", "Zrotation Yrotation Qrotation\n    End"), "unknown channel"),
    (lambda s: s.replace("Frame Time: 0.5", "Frame Time: -1"), "frame time"),
    (lambda s: s.replace("MOTION", "MOTIONS"), "no MOTION"),
    (lambda s: s.replace("  }\n}\nMOTION", "  }\nMOTION"), "file ends"),
])
def test_malformed_bvh_one_line_errors(tmp_path, mutate, message):
    path = tmp_path / "bad.bvh"
    path.write_text(mutate(SMALL))
    with pytest.raises(InputError) as info:
        read_bvh(path, units="cm")
    text = str(info.value)
    assert message in text and str(path) in text and "\n" not in text


def test_missing_file_and_bad_units(tmp_path):
    with pytest.raises(InputError, match="cannot read"):
        read_bvh(tmp_path / "absent.bvh")
    path = tmp_path / "small.bvh"
    path.write_text(SMALL)
    with pytest.raises(InputError, match="unknown BVH units"):
        read_bvh(path, units="furlong")
    with pytest.raises(InputError, match="positive"):
        read_bvh(path, units=-1.0)


MIXAMO = """HIERARCHY
ROOT mixamorig:Hips
{
  OFFSET 0 100 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT mixamorig:Spine
  {
    OFFSET 0 10 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    JOINT mixamorig:Spine1
    {
      OFFSET 0 12 0
      CHANNELS 3 Zrotation Xrotation Yrotation
      JOINT mixamorig:Spine2
      {
        OFFSET 0 14 0
        CHANNELS 3 Zrotation Xrotation Yrotation
        JOINT mixamorig:Neck
        {
          OFFSET 0 16 0
          CHANNELS 3 Zrotation Xrotation Yrotation
          JOINT mixamorig:Head
          {
            OFFSET 0 10 0
            CHANNELS 3 Zrotation Xrotation Yrotation
            JOINT mixamorig:HeadTop_End
            {
              OFFSET 0 20 0
              CHANNELS 3 Zrotation Xrotation Yrotation
              End Site
              {
                OFFSET 0 1 0
              }
            }
          }
        }
        JOINT mixamorig:LeftShoulder
        {
          OFFSET 6 10 0
          CHANNELS 3 Zrotation Xrotation Yrotation
          JOINT mixamorig:LeftArm
          {
            OFFSET 12 0 0
            CHANNELS 3 Zrotation Xrotation Yrotation
            JOINT mixamorig:LeftForeArm
            {
              OFFSET 28 0 0
              CHANNELS 3 Zrotation Xrotation Yrotation
              JOINT mixamorig:LeftHand
              {
                OFFSET 26 0 0
                CHANNELS 3 Zrotation Xrotation Yrotation
                End Site
                {
                  OFFSET 8 0 0
                }
              }
            }
          }
        }
        JOINT mixamorig:RightShoulder
        {
          OFFSET -6 10 0
          CHANNELS 3 Zrotation Xrotation Yrotation
          JOINT mixamorig:RightArm
          {
            OFFSET -12 0 0
            CHANNELS 3 Zrotation Xrotation Yrotation
            JOINT mixamorig:RightForeArm
            {
              OFFSET -28 0 0
              CHANNELS 3 Zrotation Xrotation Yrotation
              JOINT mixamorig:RightHand
              {
                OFFSET -26 0 0
                CHANNELS 3 Zrotation Xrotation Yrotation
                End Site
                {
                  OFFSET -8 0 0
                }
              }
            }
          }
        }
      }
    }
  }
  JOINT mixamorig:LeftUpLeg
  {
    OFFSET 9 -5 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    JOINT mixamorig:LeftLeg
    {
      OFFSET 0 -44 0
      CHANNELS 3 Zrotation Xrotation Yrotation
      JOINT mixamorig:LeftFoot
      {
        OFFSET 0 -42 0
        CHANNELS 3 Zrotation Xrotation Yrotation
        End Site
        {
          OFFSET 0 -5 12
        }
      }
    }
  }
  JOINT mixamorig:RightUpLeg
  {
    OFFSET -9 -5 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    JOINT mixamorig:RightLeg
    {
      OFFSET 0 -44 0
      CHANNELS 3 Zrotation Xrotation Yrotation
      JOINT mixamorig:RightFoot
      {
        OFFSET 0 -42 0
        CHANNELS 3 Zrotation Xrotation Yrotation
        End Site
        {
          OFFSET 0 -5 12
        }
      }
    }
  }
}
MOTION
Frames: 1
Frame Time: 0.0333333
""" + " ".join(["0"] * (6 + 3 * 20)) + "\n"


def test_mixamo_names_and_centimetres(tmp_path):
    path = tmp_path / "mixamo.bvh"
    path.write_text(MIXAMO)
    motion = read_bvh(path)
    assert motion.units_m == 0.01 and "'cm'" in motion.units_source
    joints = motion.contract_joint_positions()[0]
    np.testing.assert_allclose(joints[JOINT_INDEX["pelvis"]], [0, 1.0, 0])
    np.testing.assert_allclose(joints[JOINT_INDEX["neck"]], [0, 1.52, 0])
    np.testing.assert_allclose(joints[JOINT_INDEX["head"]], [0, 1.72, 0])   # Head..HeadTop_End midpoint
    np.testing.assert_allclose(joints[JOINT_INDEX["l_wrist"]], [0.72, 1.46, 0])
    np.testing.assert_allclose(joints[JOINT_INDEX["r_ankle"]], [-0.09, 0.09, 0])
    assert motion.joint_index("LeftArm") == motion.joint_index("mixamorig:LeftArm")


def test_write_bvh_round_trip(tmp_path):
    body_mod = pytest.importorskip("depthtrack.body")
    from depthtrack.io.bvh import BVH_FROM_CAMERA, write_bvh

    body = body_mod.BodyModel.default(mesh="decimated")
    rng = np.random.default_rng(3)
    poses = rng.normal(0, 0.7, (30, body.dof))
    poses[:, :3] = rng.normal(0, 0.5, (30, 3)) + [0, 0, 3]
    path = tmp_path / "track.bvh"
    write_bvh(path, body, poses, fps=25)
    motion = read_bvh(path)
    assert motion.units_m == 1.0 and motion.n_frames == 30 and motion.fps == pytest.approx(25)
    expected = body.joint_positions(poses) @ BVH_FROM_CAMERA.T
    assert np.abs(motion.contract_joint_positions() - expected).max() < 1e-3
    # y up: the head is above the ankles at the zero pose.
    write_bvh(path, body, np.zeros((1, body.dof)), fps=25)
    rest = read_bvh(path).contract_joint_positions()[0]
    assert rest[JOINT_INDEX["head"], 1] > rest[JOINT_INDEX["l_ankle"], 1] + 1.4


def _walking_bvh(tmp_path, rows):
    """SMALL's skeleton with the given root rows (x y z rz ry rx lz ly lx), 30 fps, metres."""
    head = SMALL.split("MOTION")[0]
    text = head + f"MOTION\nFrames: {len(rows)}\nFrame Time: {1 / 30}\n"
    text += "\n".join(" ".join(f"{v:g}" for v in r) for r in rows) + "\n"
    path = tmp_path / "m.bvh"
    path.write_text(text)
    return read_bvh(path, units="m")


def test_leading_jump_finds_a_calibration_frame(tmp_path):
    # frame 0 stands elsewhere in another pose (a calibration T-pose), then a smooth walk at 1.5 m/s
    walk = [[0.05 * i, 1.0, 0.0, 0, 0, 0, 10, 0, 0] for i in range(1, 40)]
    motion = _walking_bvh(tmp_path, [[3.0, 1.0, 2.0, 0, 0, 0, 90, 0, 0]] + walk)
    assert motion.leading_jump() == 1
    assert _walking_bvh(tmp_path, walk).leading_jump() == 0


def test_leading_jump_ignores_fast_motion_later(tmp_path):
    # a jump 2 s into the motion is not a leading calibration frame
    rows = [[0.05 * i + (2.0 if i >= 60 else 0.0), 1.0, 0.0, 0, 0, 0, 10, 0, 0] for i in range(90)]
    assert _walking_bvh(tmp_path, rows).leading_jump() == 0
