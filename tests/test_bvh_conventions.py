"""BVH joint names of every common convention, found by name and structure, or by a joint map.

Each convention is a small hand-made skeleton written here as BVH text: the same T-pose
body (centimetres: y up, facing +z, the subject's left +x) under that convention's joint
names, layout, units, rotation orders and quirks.
"""
import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from depthtrack.contract import JOINT_INDEX as C
from depthtrack.errors import InputError
from depthtrack.io.bvh import UNIT_NAMES, map_joints, read_bvh, split_name

REPO = Path(__file__).resolve().parents[1]

#: (role, parent role, offset in cm). Optional roles a convention leaves out hand their
#: offset on to their children.
ROLES = [
    ("root", None, (0, 0, 0)),
    ("legroot", "root", (0, 0, 0)),
    ("spine", "root", (0, 10, 0)), ("chest", "spine", (0, 25, 0)),
    ("neckbase", "chest", (0, 12, 0)), ("neck", "neckbase", (0, 8, 0)), ("head", "neck", (0, 10, 0)),
]
for _s, _x in (("l", 1), ("r", -1)):
    ROLES += [
        (f"{_s}_hipjoint", "legroot", (_x * 4, -4, 0)), (f"{_s}_thigh", f"{_s}_hipjoint", (_x * 5, -2, 0)),
        (f"{_s}_thigh2", f"{_s}_thigh", (0, -21, 0)), (f"{_s}_knee", f"{_s}_thigh2", (0, -21, 0)),
        (f"{_s}_ankle", f"{_s}_knee", (0, -41, 0)), (f"{_s}_toe", f"{_s}_ankle", (0, -6, 12)),
        (f"{_s}_clavicle", "chest", (_x * 3, 18, 0)), (f"{_s}_upperarm", f"{_s}_clavicle", (_x * 15, 2, 0)),
        (f"{_s}_upperarm2", f"{_s}_upperarm", (_x * 14, 0, 0)), (f"{_s}_elbow", f"{_s}_upperarm2", (_x * 14, 0, 0)),
        (f"{_s}_wrist", f"{_s}_elbow", (_x * 25, 0, 0)), (f"{_s}_fingers", f"{_s}_wrist", (_x * 8, 0, 0)),
    ]
PARENT = {r: p for r, p, _ in ROLES}
OFFSET = {r: np.array(o, float) for r, _, o in ROLES}


def rest_cm(role):
    """Rest position of a role in the full skeleton, cm (root at the origin)."""
    pos = np.zeros(3)
    while role is not None:
        pos = pos + OFFSET[role]
        role = PARENT[role]
    return pos


def bvh_text(names, units_m, extras=(), orders=("ZYX", "ZYX"), root_offset=(0, 0, 0), root_pos=(0, 100, 0),
             head_end=True, neck_end=False, frame1=None, newline="\n", frames_sep=" "):
    """BVH text of the skeleton under ``names`` ({role: name}, roles not named are left out).

    ``extras``: (name, parent role, offset cm) extra joints. ``orders``: the root's and the
    other joints' rotation orders. ``frame1``: {name: {axis: degrees}} for a second frame.
    """
    scale = 0.01 / units_m
    present = [r for r, _, _ in ROLES if r in names]

    def anchor(role):
        """Nearest present ancestor, and the offset from it (cm)."""
        off, p = OFFSET[role].copy(), PARENT[role]
        while p is not None and p not in names:
            off, p = off + OFFSET[p], PARENT[p]
        return p, off

    kids = {}
    for r in present[1:]:
        p, off = anchor(r)
        kids.setdefault(p, []).append((names[r], off, r))
    for name, parent, off in extras:
        kids.setdefault(parent, []).append((name, np.array(off, float), None))
    channel_order = []
    lines = ["HIERARCHY"]

    def emit(name, off, role, depth, root=False):
        pad = "  " * depth
        lines.append(f"{pad}{'ROOT' if root else 'JOINT'} {name}")
        lines.append(f"{pad}{{")
        lines.append(f"{pad}  OFFSET {' '.join(f'{v * scale:.6f}' for v in off)}")
        order = orders[0] if root else orders[1]
        rot = " ".join(f"{a}rotation" for a in order)
        lines.append(f"{pad}  CHANNELS {'6 Xposition Yposition Zposition ' if root else '3 '}{rot}")
        channel_order.append((name, (["Xp", "Yp", "Zp"] if root else []) + list(order)))
        children = kids.get(role, []) if role is not None else []
        if (role == "head" and head_end) or (role == "neck" and neck_end):
            lines.extend([f"{pad}  End Site", f"{pad}  {{", f"{pad}    OFFSET 0 {10 * scale:.6f} 0", f"{pad}  }}"])
        elif not children:
            lines.extend([f"{pad}  End Site", f"{pad}  {{", f"{pad}    OFFSET 0 {2 * scale:.6f} 0", f"{pad}  }}"])
        for child, coff, crole in children:
            emit(child, coff, crole, depth + 1)
        lines.append(f"{pad}}}")

    emit(names["root"], np.array(root_offset, float), "root", 0, root=True)

    def row(changes):
        values = []
        for name, chans in channel_order:
            for ch in chans:
                if ch.endswith("p"):
                    values.append(root_pos["XYZ".index(ch[0])] * scale)
                else:
                    values.append((changes or {}).get(name, {}).get(ch, 0.0))
        return " ".join(f"{v:.6f}" for v in values)

    lines += ["MOTION", f"Frames:{frames_sep}2", "Frame Time: 0.0083333", row({}), row(frame1)]
    return newline.join(lines) + newline


def side_names(template, roles):
    """{role: name} for both sides from templates using {Side} {side} {S} {s}."""
    out = {}
    for role, t in template.items():
        if role[:2] == "x_":
            for s, Side, side in (("l", "Left", "left"), ("r", "Right", "right")):
                out[f"{s}_{role[2:]}"] = t.format(Side=Side, side=side, S=s.upper(), s=s)
        else:
            out[role] = t
    return out


LIMB = ("clavicle", "upperarm", "elbow", "wrist", "hipjoint", "thigh", "knee", "ankle", "toe")


def convention(root, spine, chest, neck, head, *limbs, neckbase=None, legroot=None, thigh2=None,
               upperarm2=None, fingers=None):
    t = {"root": root, "spine": spine, "chest": chest, "neck": neck, "head": head, "neckbase": neckbase,
         "legroot": legroot}
    for part, name in zip(LIMB, limbs):
        t["x_" + part] = name
    t["x_thigh2"], t["x_upperarm2"], t["x_fingers"] = thigh2, upperarm2, fingers
    return side_names({k: v for k, v in t.items() if v is not None}, None)


#: name -> (names, units name, expected detect_convention, bvh_text keyword arguments, extras)
CONVENTIONS = {
    "cgspeed MotionBuilder": (convention(
        "Hips", "LowerBack", "Spine1", "Neck1", "Head", "{Side}Shoulder", "{Side}Arm", "{Side}ForeArm",
        "{Side}Hand", "{S}HipJoint", "{Side}UpLeg", "{Side}Leg", "{Side}Foot", "{Side}ToeBase", neckbase="Neck"),
        "cmu", "CMU cgspeed MotionBuilder", {}, []),
    "cgspeed 3dsMax": (convention(
        "Hips", "lowerback", "Chest", "Neck", "Head", "{Side}Collar", "{Side}Shoulder", "{Side}Elbow",
        "{Side}Wrist", "{S}HipJoint", "{Side}Hip", "{Side}Knee", "{Side}Ankle", "{Side}Toe",
        neckbase="lowerneck", fingers="{s}hand"),
        "cmu", "CMU cgspeed 3dsMax", {"orders": ("ZYX", "ZXY")}, []),
    "cgspeed Daz": (convention(
        "hip", "abdomen", "chest", "neck", "head", "{s}Collar", "{s}Shldr", "{s}ForeArm", "{s}Hand",
        "{s}Buttock", "{s}Thigh", "{s}Shin", "{s}Foot", None),
        "cm", "CMU cgspeed Daz",
        {"orders": ("ZYX", "ZXY"), "newline": "\r\n", "frames_sep": "\t", "head_end": False},
        [("leftEye", "head", (3.5, 8, 8)), ("rightEye", "head", (-3.5, 8, 8))]),
    "Reallusion CC": (convention(
        "CC_Base_Hip", "CC_Base_Waist", "CC_Base_Spine02", "CC_Base_NeckTwist01", "CC_Base_Head",
        "CC_Base_{S}_Clavicle", "CC_Base_{S}_Upperarm", "CC_Base_{S}_Forearm", "CC_Base_{S}_Hand", None,
        "CC_Base_{S}_Thigh", "CC_Base_{S}_Calf", "CC_Base_{S}_Foot", "CC_Base_{S}_ToeBase",
        legroot="CC_Base_Pelvis"),
        "cm", "Reallusion CC", {"root_offset": (0, 100, 0), "root_pos": (0, 2, 0), "head_end": False},
        [("CC_Base_L_Eye", "head", (3.2, 7, 8)), ("CC_Base_R_Eye", "head", (-3.2, 7, 8)),
         ("CC_Base_L_UpperarmTwist01", "l_upperarm", (0, 0, 0)),
         ("CC_Base_L_CalfTwist01", "l_knee", (0, 0, 0))]),
    "Mixamo": (convention(
        "mixamorig:Hips", "mixamorig:Spine", "mixamorig:Spine2", "mixamorig:Neck", "mixamorig:Head",
        "mixamorig:{Side}Shoulder", "mixamorig:{Side}Arm", "mixamorig:{Side}ForeArm", "mixamorig:{Side}Hand",
        None, "mixamorig:{Side}UpLeg", "mixamorig:{Side}Leg", "mixamorig:{Side}Foot", "mixamorig:{Side}ToeBase"),
        "cm", "Mixamo", {"head_end": False}, [("mixamorig:HeadTop_End", "head", (0, 18, 0))]),
    "DeepMimic": (convention(
        "Hips", None, "Spine1", "Neck1", None, None, "{Side}Arm", "{Side}ForeArm", "{Side}Hand", None,
        "{Side}UpLeg", "{Side}Leg", "{Side}Foot", None),
        "m", "DeepMimic", {"neck_end": True, "head_end": False}, []),
    "SMPL": (convention(
        "pelvis", "spine1", "spine3", "neck", "head", "{side}_collar", "{side}_shoulder", "{side}_elbow",
        "{side}_wrist", None, "{side}_hip", "{side}_knee", "{side}_ankle", "{side}_foot", fingers="{side}_hand"),
        "m", "SMPL", {}, []),
    "SMPL L_": (convention(
        "Pelvis", "Spine1", "Spine3", "Neck", "Head", "{S}_Collar", "{S}_Shoulder", "{S}_Elbow", "{S}_Wrist",
        None, "{S}_Hip", "{S}_Knee", "{S}_Ankle", "{S}_Foot", fingers="{S}_Hand"),
        "m", "SMPL", {}, []),
    "Xsens MVN": (convention(
        "Pelvis", "L5", "T8", "Neck", "Head", "{Side}Shoulder", "{Side}UpperArm", "{Side}ForeArm",
        "{Side}Hand", None, "{Side}UpperLeg", "{Side}LowerLeg", "{Side}Foot", "{Side}Toe"),
        "cm", "Xsens MVN", {}, []),
    "Rokoko": (convention(
        "Hips", "Spine1", "Spine4", "Neck", "Head", "{Side}Shoulder", "{Side}Arm", "{Side}ForeArm",
        "{Side}Hand", None, "{Side}Thigh", "{Side}Shin", "{Side}Foot", "{Side}Toe"),
        "cm", "Rokoko", {}, []),
    "Perception Neuron": (convention(
        "Hips", "Spine", "Spine3", "Neck", "Head", "{Side}Shoulder", "{Side}Arm", "{Side}ForeArm",
        "{Side}Hand", None, "{Side}UpLeg", "{Side}Leg", "{Side}Foot", None, fingers="{Side}InHandIndex"),
        "cm", "Perception Neuron", {}, []),
    "Blender Rigify": (convention(
        "DEF-spine", "DEF-spine.001", "DEF-spine.003", "DEF-spine.004", "DEF-spine.006", "DEF-shoulder.{S}",
        "DEF-upper_arm.{S}", "DEF-forearm.{S}", "DEF-hand.{S}", "DEF-pelvis.{S}", "DEF-thigh.{S}",
        "DEF-shin.{S}", "DEF-foot.{S}", "DEF-toe.{S}", thigh2="DEF-thigh.{S}.001",
        upperarm2="DEF-upper_arm.{S}.001"),
        "m", "Blender Rigify", {}, []),
}

#: Contract joint -> the role whose position it is.
CONTRACT_ROLE = {"pelvis": "root", "neck": "neck"}
for _s in "lr":
    CONTRACT_ROLE.update({f"{_s}_shoulder": f"{_s}_upperarm", f"{_s}_elbow": f"{_s}_elbow",
                          f"{_s}_wrist": f"{_s}_wrist", f"{_s}_hip": f"{_s}_thigh",
                          f"{_s}_knee": f"{_s}_knee", f"{_s}_ankle": f"{_s}_ankle"})


def _write(tmp_path, text, name="take.bvh"):
    path = tmp_path / name
    path.write_bytes(text.encode())
    return path


@pytest.mark.parametrize("key", list(CONVENTIONS))
def test_convention_maps_to_the_right_joints(tmp_path, key):
    names, unit, detected, kwargs, extras = CONVENTIONS[key]
    units_m = UNIT_NAMES[unit]
    left_elbow = names["l_elbow"]
    text = bvh_text(names, units_m, extras=extras, frame1={left_elbow: {"Z": 90.0}}, **kwargs)
    motion = read_bvh(_write(tmp_path, text))
    # units inferred from the leg and the convention, and reported
    assert motion.units_m == pytest.approx(units_m, rel=1e-12), motion.units_source
    assert f"'{unit}'" in motion.units_source and detected in motion.units_source
    assert motion.convention() == detected
    joints = motion.contract_joint_positions()
    # Reallusion: the root's OFFSET (the hip height) plus its position channels
    root = np.array(kwargs.get("root_offset", (0, 0, 0)), float) + kwargs.get("root_pos", (0, 100, 0))
    for contract, role in CONTRACT_ROLE.items():
        expected = (rest_cm(role) + root) * 0.01
        np.testing.assert_allclose(joints[0, C[contract]], expected, atol=1e-6, err_msg=contract)
    # the head centre is above the neck, on the body's axis
    head = joints[0, C["head"]] - joints[0, C["neck"]]
    assert 0.05 < head[1] < 0.25 and abs(head[0]) < 1e-6, head
    # frame 2: the left elbow bent 90 degrees about z turns the forearm from +x to +y
    np.testing.assert_allclose(joints[1, C["l_wrist"]] - joints[1, C["l_elbow"]], [0, 0.25, 0], atol=1e-6)


def test_daz_rotation_order_is_per_joint(tmp_path):
    names, _, _, kwargs, extras = CONVENTIONS["cgspeed Daz"]
    # Zrotation Xrotation Yrotation: R = Rz Rx Ry; Ry(90) takes +x to -z, then Rx(90) -z to +y
    # (in the ZYX order the same angles would leave the forearm along -z).
    text = bvh_text(names, 0.01, extras=extras, frame1={"lForeArm": {"X": 90.0, "Y": 90.0}}, **kwargs)
    assert "\r\n" in text and "Frames:\t2" in text
    joints = read_bvh(_write(tmp_path, text)).contract_joint_positions()
    np.testing.assert_allclose(joints[1, C["l_wrist"]] - joints[1, C["l_elbow"]], [0, 0.25, 0], atol=1e-6)


def _arm(tmp_path, names, name):
    full = dict(CONVENTIONS["cgspeed MotionBuilder"][0])
    for k in [k for k in full if k[2:] in ("clavicle", "upperarm", "elbow", "wrist")]:
        del full[k]
    full.update(names)
    return read_bvh(_write(tmp_path, bvh_text(full, 0.01), name))


def test_left_shoulder_is_decided_by_structure_not_name(tmp_path):
    both = lambda d: {**d, **{"r" + k[1:]: v.replace("Left", "Right") for k, v in d.items()}}
    expected = lambda role: (rest_cm(role) + [0, 100, 0]) * 0.01
    # MotionBuilder: LeftShoulder above LeftArm is the clavicle
    mb = _arm(tmp_path, both({"l_clavicle": "LeftShoulder", "l_upperarm": "LeftArm", "l_elbow": "LeftForeArm",
                              "l_wrist": "LeftHand"}), "mb.bvh")
    assert mb.joint_names[mb.contract_joint_indices()["l_shoulder"][1]] == "LeftArm"
    # 3dsMax: LeftShoulder, the elbow's parent, is the upper arm (and LeftCollar the clavicle)
    mx = _arm(tmp_path, both({"l_clavicle": "LeftCollar", "l_upperarm": "LeftShoulder", "l_elbow": "LeftElbow",
                              "l_wrist": "LeftWrist"}), "max.bvh")
    # no clavicle at all: LeftShoulder straight under the chest, parent of LeftForeArm
    bare = _arm(tmp_path, both({"l_upperarm": "LeftShoulder", "l_elbow": "LeftForeArm", "l_wrist": "LeftHand"}),
                "bare.bvh")
    for motion in (mx, bare):
        assert motion.joint_names[motion.contract_joint_indices()["l_shoulder"][1]] == "LeftShoulder"
    for motion in (mb, mx, bare):
        joints = motion.contract_joint_positions()[0]
        np.testing.assert_allclose(joints[C["l_shoulder"]], expected("l_upperarm"), atol=1e-6)
        np.testing.assert_allclose(joints[C["r_shoulder"]], expected("r_upperarm"), atol=1e-6)
        np.testing.assert_allclose(joints[C["l_wrist"]], expected("l_wrist"), atol=1e-6)


def test_name_splitting():
    assert split_name("mixamorig:LeftUpLeg") == ("l", "upleg")
    assert split_name("CC_Base_R_Calf") == ("r", "calf")
    assert split_name("DEF-thigh.L") == ("l", "thigh")
    assert split_name("DEF-thigh.L.001") == ("l", "thigh001")
    assert split_name("lShldr") == ("l", "shldr")
    assert split_name("LHipJoint") == ("l", "hipjoint")
    assert split_name("lowerback") == ("", "lowerback")
    assert split_name("right_wrist") == ("r", "wrist")
    assert split_name("R_Ankle") == ("r", "ankle")
    assert split_name("Neck1") == ("", "neck1")


def _odd_skeleton():
    names = dict(CONVENTIONS["cgspeed MotionBuilder"][0])
    for s, S in (("l", "L"), ("r", "R")):
        names[f"{s}_upperarm"], names[f"{s}_elbow"], names[f"{s}_wrist"] = f"Bone{S}1", f"Bone{S}2", f"Bone{S}3"
    return names


def test_refusal_lists_found_and_needed_names_and_a_joint_map_fixes_it(tmp_path):
    path = _write(tmp_path, bvh_text(_odd_skeleton(), 0.01))
    motion = read_bvh(path)
    with pytest.raises(InputError) as err:
        motion.contract_joint_positions()
    text = str(err.value)
    assert "\n" not in text and "take.bvh" in text
    for needed in ("l_shoulder", "l_elbow", "l_wrist", "r_elbow", "LeftForeArm/LeftElbow", "--joint-map"):
        assert needed in text
    assert "BoneL2" in text and "LeftUpLeg" in text          # the joints the file has
    joint_map = {"l_shoulder": "BoneL1", "l_elbow": "BoneL2", "l_wrist": "BoneL3",
                 "r_shoulder": "BoneR1", "r_elbow": "BoneR2", "r_wrist": "BoneR3"}
    map_path = tmp_path / "map.json"
    map_path.write_text(json.dumps(joint_map))
    mapped = read_bvh(path, joint_map=map_path)
    joints = mapped.contract_joint_positions()[0]
    np.testing.assert_allclose(joints[C["l_elbow"]], (rest_cm("l_elbow") + [0, 100, 0]) * 0.01, atol=1e-6)
    # a map naming a joint the file lacks, or one of our joints that does not exist
    with pytest.raises(InputError, match="does not have"):
        read_bvh(path, joint_map={"l_elbow": "Nope"})
    with pytest.raises(InputError, match="unknown joints"):
        map_joints(["Hips"], [-1], [], {"l_elbo": "Hips"})


def test_synth_refuses_an_unmapped_skeleton_and_takes_a_joint_map(tmp_path):
    path = _write(tmp_path, bvh_text(_odd_skeleton(), 0.01))
    out = tmp_path / "seq"
    cmd = [sys.executable, "-m", "depthtrack", "synth", str(path), str(out), "--seconds", "0.04",
           "--noise", "none", "--quiet"]
    run = subprocess.run(cmd, capture_output=True, text=True, cwd=REPO)
    assert run.returncode == 2 and not out.exists()
    assert len(run.stderr.strip().splitlines()) == 1 and "--joint-map" in run.stderr
    (tmp_path / "map.json").write_text(json.dumps({f"{s}_{j}": f"Bone{s.upper()}{k}" for s in "lr" for k, j in
                                                   ((1, "shoulder"), (2, "elbow"), (3, "wrist"))}))
    run = subprocess.run(cmd + ["--joint-map", str(tmp_path / "map.json")], capture_output=True, text=True,
                         cwd=REPO)
    assert run.returncode == 0, run.stderr
    meta = json.loads((out / "sequence.json").read_text())
    assert meta["synth"]["source"]["joint_map"]["l_elbow"] == "BoneL2"


# ------------------------------------------------------------------ the shared clips
def _clips(data):
    return sorted(p for d in ("cmu-extra", "motions", "cmu") for p in (data / d).glob("*.bvh"))


#: Clips whose first frame after the calibration pose is not upright: the back stroke
#: (lying on a support).
NOT_UPRIGHT = {"126_01.bvh"}


def test_every_shared_clip_imports_and_retargets_to_sane_joints(shared_data):
    from dataclasses import replace

    from depthtrack.body import BodyModel
    from depthtrack.motion.retarget import canonical_axes, retarget, subject_height

    clips = _clips(shared_data)
    assert len(clips) >= 36
    body = BodyModel.default(mesh="decimated")
    for path in clips:
        full = read_bvh(path)
        # the first seconds for the calibration pose, every n-th frame for the retargeting
        motion = replace(full, frames=full.frames[:int(2 * full.fps)], _cache={})
        first = motion.leading_jump()
        joints = motion.contract_joint_positions()[first]
        for s in "lr":
            leg = (np.linalg.norm(joints[C[f"{s}_knee"]] - joints[C[f"{s}_hip"]])
                   + np.linalg.norm(joints[C[f"{s}_ankle"]] - joints[C[f"{s}_knee"]]))
            assert 0.7 < leg < 1.0, (path.name, leg)
        if path.name not in NOT_UPRIGHT:
            assert joints[C["head"]][1] > joints[C["pelvis"]][1] + 0.3, path.name
            assert joints[C["neck"]][1] > joints[C["l_hip"]][1] + 0.3, path.name

        motion = replace(full, frames=full.frames[::max(1, full.n_frames // 30)], _cache={})
        same = body.scaled(height=subject_height(motion, body))
        assert 1.3 < same.height < 2.0, (path.name, same.height)
        T = np.eye(4)
        T[:3, :3] = canonical_axes(motion)
        ours = same.joint_positions(retarget(motion, same, T))
        theirs = motion.contract_joint_positions() @ T[:3, :3].T
        hips = lambda j: j[:, [C["l_hip"], C["r_hip"]]].mean(axis=1)[:, None]
        error = np.linalg.norm((ours - hips(ours)) - (theirs - hips(theirs)), axis=-1)
        assert error.mean() < 0.08, (path.name, error.mean())
        for a, b in (("l_elbow", "l_wrist"), ("r_hip", "r_knee"), ("l_knee", "l_ankle"), ("neck", "head")):
            u, v = ours[:, C[b]] - ours[:, C[a]], theirs[:, C[b]] - theirs[:, C[a]]
            cos = np.sum(u * v, -1) / np.linalg.norm(u, axis=-1) / np.linalg.norm(v, axis=-1)
            assert cos.min() > 0.9999, (path.name, a, b)


#: CMU MotionBuilder -> 3dsMax names (cgspeed's two releases of the same takes).
TO_3DSMAX = {"LeftUpLeg": "LeftHip", "LeftLeg": "LeftKnee", "LeftFoot": "LeftAnkle", "LeftToeBase": "LeftToe",
             "LowerBack": "lowerback", "Spine": "Chest", "Spine1": "Chest2", "Neck": "lowerneck", "Neck1": "Neck",
             "LeftShoulder": "LeftCollar", "LeftArm": "LeftShoulder", "LeftForeArm": "LeftElbow",
             "LeftHand": "LeftWrist", "LeftFingerBase": "lhand"}
TO_3DSMAX.update({k.replace("Left", "Right"): v.replace("Left", "Right").replace("lhand", "rhand")
                  for k, v in TO_3DSMAX.items() if "Left" in k})


def test_back_stroke_in_3dsmax_names_loads_to_the_same_joints(shared_data, tmp_path):
    original = shared_data / "cmu" / "126_01.bvh"
    text = original.read_text()
    head, _, motion_part = text.partition("MOTION")
    renamed = re.sub(r"^(\s*(?:ROOT|JOINT)\s+)(\S+)", lambda m: m.group(1) + TO_3DSMAX.get(m.group(2), m.group(2)),
                     head, flags=re.MULTILINE)
    assert "LeftElbow" in renamed and "LeftArm" not in renamed
    lines = motion_part.splitlines()[1:]
    lines = ["", "Frames: 300", lines[1]] + lines[2:302]
    path = _write(tmp_path, renamed + "MOTION" + "\n".join(lines) + "\n", "126_01_3dsmax.bvh")
    a = read_bvh(original)
    b = read_bvh(path)
    assert b.convention() == "CMU cgspeed 3dsMax" and b.units_m == a.units_m
    np.testing.assert_array_equal(b.contract_joint_positions(), a.contract_joint_positions()[:len(b.frames)])


def test_swim_reads_bvh_through_the_same_mapping(tmp_path):
    from depthtrack.swim.mocap import load_swim_mocap
    from depthtrack.swim.stickfigure import SWIM_INDEX

    path = _write(tmp_path, bvh_text(_odd_skeleton(), 0.01))
    with pytest.raises(InputError, match="--joint-map"):
        load_swim_mocap(path)
    joint_map = {f"{s}_{j}": f"Bone{s.upper()}{k}" for s in "lr" for k, j in ((1, "shoulder"), (2, "elbow"), (3, "wrist"))}
    mocap = load_swim_mocap(path, joint_map=joint_map)
    np.testing.assert_allclose(mocap.joints[0, SWIM_INDEX["l_elbow"]], (rest_cm("l_elbow") + [0, 100, 0]) * 0.01,
                               atol=1e-6)
