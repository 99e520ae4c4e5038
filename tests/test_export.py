"""Exports for other tools: glTF/GLB, C3D, BVH (T-pose, --up), JSON, CSV, and the CLI."""
import json

import numpy as np
import pytest

from depthtrack.body import BodyModel
from depthtrack.body.markers import MARKER_NAMES, marker_positions
from depthtrack.cli import main
from depthtrack.contract import JOINT_INDEX, JOINT_NAMES
from depthtrack.io.bvh import read_bvh, write_bvh
from depthtrack.export.axes import Y_UP_FROM_CAMERA, Z_UP_FROM_CAMERA
from depthtrack.export.bvh import bvh_text
from depthtrack.export.registry import EXPORTERS, write_exports
from depthtrack.io.track_output import hold_last_pose, write_track

FPS = 30.0
F = 6
MISSING = 2          # a frame without a pose


@pytest.fixture(scope="module")
def track(tmp_path_factory):
    """A scaled body, 6 random poses (frame 2 unknown) and the track directory of them."""
    body = BodyModel.default(height=1.62)
    rng = np.random.default_rng(7)
    poses = np.tile(body.default_pose((0.1, -0.2, 3.0)), (F, 1))
    poses[:, 3:] += rng.normal(0.0, 0.25, (F, 45))
    poses[:, :3] += rng.normal(0.0, 0.05, (F, 3))
    poses = body.clip(poses)
    poses[MISSING] = np.nan
    joints = np.full((F, 15, 3), np.nan)
    ok = np.all(np.isfinite(poses), axis=1)
    joints[ok] = body.joint_positions(poses[ok])
    out = write_track(tmp_path_factory.mktemp("track") / "trk", joints, poses, body.pose_names, body,
                      FPS, {"method": "hc+ep"})
    return {"body": body, "poses": poses, "joints": joints, "dir": out}


def _accessor(gl, index):
    """(count, width) float array of an accessor of a loaded GLB."""
    acc = gl.accessors[index]
    view = gl.bufferViews[acc.bufferView]
    width = {"SCALAR": 1, "VEC3": 3, "VEC4": 4, "MAT4": 16}[acc.type]
    blob = gl.binary_blob()
    start = (view.byteOffset or 0) + (acc.byteOffset or 0)
    return np.frombuffer(blob, np.float32, acc.count * width, start).reshape(acc.count, width).astype(float)


def _trs(translation, quat):
    from depthtrack.body.rotations import quat_to_matrix
    m = np.eye(4)
    m[:3, :3] = quat_to_matrix(np.asarray(quat, float))
    m[:3, 3] = translation
    return m


def test_glb_hierarchy_animation_and_bind(track, tmp_path):
    import pygltflib
    import trimesh

    body, poses = track["body"], track["poses"]
    path = write_exports(tmp_path, body, poses, FPS, ["glb"])["glb"]
    scene = trimesh.load(path)
    assert len(scene.geometry) == 1
    assert len(next(iter(scene.geometry.values())).vertices) == body.mesh.num_vertices

    gl = pygltflib.GLTF2().load_binary(str(path))
    names = [n.name for n in gl.nodes]
    node = {n: i for i, n in enumerate(names)}
    for j, name in enumerate(body.joint_names):          # the tree is our kinematic tree
        kids = {names[c] for c in gl.nodes[node[name]].children or []}
        assert kids >= {body.joint_names[c] for c in np.flatnonzero(body.parents == j)}
    assert "head_centre" in {names[c] for c in gl.nodes[node["neck"]].children}
    skin = gl.skins[0]
    assert [names[i] for i in skin.joints] == list(body.joint_names)

    # inverse bind matrices: rest world of each joint times its IBM is the identity
    ibm = _accessor(gl, skin.inverseBindMatrices).reshape(-1, 4, 4).transpose(0, 2, 1)
    rest_world = {}
    for j, name in enumerate(body.joint_names):
        t = np.eye(4)
        t[:3, 3] = gl.nodes[node[name]].translation
        p = body.parents[j]
        rest_world[j] = t if p < 0 else rest_world[p] @ t
    for j in range(len(body.joint_names)):
        assert np.allclose(rest_world[j] @ ibm[j], np.eye(4), atol=1e-6)
    # ... so skinning the bind mesh with them gives the body's rest surface back (y up)
    from depthtrack.body.gltf import load_skinned_gltf
    loaded = load_skinned_gltf(path)
    assert np.allclose(loaded.mesh.vertices, body.rest_vertices, atol=1e-5)

    # one keyframe per frame at frame / fps; a rotation per joint node, the root's translation
    anim = gl.animations[0]
    targets = {(names[c.target.node], c.target.path) for c in anim.channels}
    assert targets == {(n, "rotation") for n in body.joint_names} | {("pelvis", "translation")}
    times = _accessor(gl, anim.samplers[0].input)[:, 0]
    assert np.allclose(times, np.arange(F) / FPS, atol=1e-6)
    out = {(names[c.target.node], c.target.path): _accessor(gl, anim.samplers[c.sampler].output)
           for c in anim.channels}
    assert all(len(v) == F for v in out.values())

    # the animated joints at each keyframe are the track's joints, turned y up (within 1 mm)
    filled = hold_last_pose(poses)
    expected = body.joint_positions(filled) @ Y_UP_FROM_CAMERA.T
    for k in range(F):
        world = {}
        for j, name in enumerate(body.joint_names):
            t = out[(name, "translation")][k] if name == "pelvis" else gl.nodes[node[name]].translation
            local = _trs(t, out[(name, "rotation")][k])
            p = body.parents[j]
            world[j] = local if p < 0 else world[p] @ local
        got = np.zeros((15, 3))
        for c, cname in enumerate(JOINT_NAMES):
            if cname == "head":
                h = np.append(gl.nodes[node["head_centre"]].translation, 1.0)
                got[c] = (world[body.joint_names.index("neck")] @ h)[:3]
            else:
                src = {"neck": "neck", "pelvis": "pelvis"}.get(cname, cname)
                got[c] = world[body.joint_names.index(src)][:3, 3]
        assert np.abs(got - expected[k]).max() < 1e-3, k
    # the frame without a pose holds the one before it
    assert np.allclose(expected[MISSING], expected[MISSING - 1])


def test_gltf_json_is_the_same_scene(track, tmp_path):
    import pygltflib

    path = write_exports(tmp_path, track["body"], track["poses"], FPS, ["gltf"])["gltf"]
    gl = pygltflib.GLTF2().load(str(path))
    assert gl.buffers[0].uri.startswith("data:")
    assert len(gl.animations[0].channels) == 16 and len(gl.nodes) == 17


def test_c3d_markers_and_joints_in_mm_z_up(track, tmp_path):
    import ezc3d

    body, poses, joints = track["body"], track["poses"], track["joints"]
    path = write_exports(tmp_path, body, poses, FPS, ["c3d"], joints=joints)["c3d"]
    c3d = ezc3d.c3d(str(path))
    labels = [s.strip() for s in c3d["parameters"]["POINT"]["LABELS"]["value"]]
    assert labels == list(MARKER_NAMES) + list(JOINT_NAMES) and len(MARKER_NAMES) == 39
    assert c3d["header"]["points"]["frame_rate"] == FPS
    assert c3d["parameters"]["POINT"]["UNITS"]["value"][0].strip() == "mm"
    pts = np.transpose(c3d["data"]["points"][:3], (2, 1, 0))            # (F, 54, 3)
    assert pts.shape == (F, 54, 3)
    residuals = c3d["data"]["meta_points"]["residuals"][0].T           # (F, 54)
    assert np.all(residuals[MISSING] < 0) and np.all(residuals[np.arange(F) != MISSING] >= 0)
    ok = np.arange(F) != MISSING
    want_joints = joints[ok] @ Z_UP_FROM_CAMERA.T * 1000.0
    assert np.abs(pts[ok, 39:] - want_joints).max() < 0.01                 # float32 in the file
    want_markers = marker_positions(body, poses[ok]) @ Z_UP_FROM_CAMERA.T * 1000.0
    assert np.abs(pts[ok, :39] - want_markers).max() < 0.01
    # z is up: the head is above the ankles by most of the body's height
    head, ankle = pts[0, 39 + JOINT_INDEX["head"], 2], pts[0, 39 + JOINT_INDEX["l_ankle"], 2]
    assert head - ankle > 1000.0


@pytest.mark.parametrize("up", ["y", "z"])
def test_bvh_tpose_rest_and_up_axis_round_trip(track, tmp_path, up):
    body, poses = track["body"], hold_last_pose(track["poses"])
    path = tmp_path / "t.bvh"
    path.write_text(bvh_text(body, poses, FPS, rest="tpose", up=up))
    motion = read_bvh(path, units="m")
    axes = Y_UP_FROM_CAMERA if up == "y" else Z_UP_FROM_CAMERA
    want = body.joint_positions(poses) @ axes.T
    assert np.abs(motion.contract_joint_positions() - want).max() < 1e-3
    assert motion.fps == pytest.approx(FPS, rel=1e-6)
    # rest pose: arms straight out sideways, legs straight down, along the file's axes
    rest = motion.rest_joint_positions()
    idx = motion.joint_index
    up_axis = np.array([0, 1, 0]) if up == "y" else np.array([0, 0, 1])
    for a, b, direction in (("LeftArm", "LeftHand", [1, 0, 0]), ("RightArm", "RightHand", [-1, 0, 0]),
                            ("LeftUpLeg", "LeftFoot", -up_axis), ("RightUpLeg", "RightFoot", -up_axis)):
        bone = rest[idx(b)] - rest[idx(a)]
        assert np.dot(bone / np.linalg.norm(bone), direction) > 0.9999, (a, b)


def test_bvh_with_our_rest_and_y_up_is_track_bvh(track, tmp_path):
    body, poses = track["body"], hold_last_pose(track["poses"])
    write_bvh(tmp_path / "a.bvh", body, poses, FPS)
    assert bvh_text(body, poses, FPS, rest="zero", up="y") == (tmp_path / "a.bvh").read_text()


def test_json_one_object_per_frame(track, tmp_path):
    path = write_exports(tmp_path, track["body"], track["poses"], FPS, ["json"],
                         joints=track["joints"])["json"]
    doc = json.loads(path.read_text())
    assert doc["format"] == "depthtrack-joints/1" and doc["fps"] == FPS
    assert [f["frame"] for f in doc["frames"]] == list(range(F))
    assert doc["frames"][3]["time"] == pytest.approx(3 / FPS)
    assert all(v is None for v in doc["frames"][MISSING]["joints"].values())
    got = np.array(doc["frames"][4]["joints"]["l_wrist"])
    assert np.allclose(got, track["joints"][4, JOINT_INDEX["l_wrist"]], atol=1e-6)


def test_registry_names():
    assert set(EXPORTERS) == {"glb", "gltf", "c3d", "json", "bvh", "csv"}


def test_export_cli_raw_and_smoothed(track, tmp_path, capsys):
    out = tmp_path / "ex"
    assert main(["export", str(track["dir"]), "--format", "glb,c3d,json,bvh,csv", "-o", str(out),
                 "--quiet"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["joints.csv", "joints.json", "track.bvh",
                                                     "track.c3d", "track.glb"]
    assert main(["export", str(track["dir"]), "--format", "json", "-o", str(out),
                 "--smooth", "savgol:5", "--quiet"]) == 0
    raw = json.loads((out / "joints.json").read_text())
    smooth = json.loads((out / "joints_smoothed.json").read_text())
    assert raw != smooth and smooth["frames"][MISSING]["joints"]["head"] is None
    # the raw track is untouched
    assert sorted(p.name for p in track["dir"].iterdir()) == ["body.json", "joints.csv", "poses.npz",
                                                              "summary.json", "track.bvh"]
    # bad input: one line, exit 2, nothing written
    capsys.readouterr()
    for argv in (["--format", "fbx"], ["--smooth", "savgol:4"], ["--up", "x"]):
        code = None
        try:
            code = main(["export", str(track["dir"]), "-o", str(tmp_path / "bad"), *argv])
        except SystemExit as exc:       # argparse choices
            code = exc.code
        assert code == 2
        err = capsys.readouterr().err
        assert "Traceback" not in err and argv[1] in err.strip().splitlines()[-1]
        assert not (tmp_path / "bad").exists()
    # the track itself is no export place: its track.bvh and joints.csv would be replaced
    before = (track["dir"] / "track.bvh").read_bytes()
    assert main(["export", str(track["dir"]), "--format", "bvh", "-o", str(track["dir"])]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "is the track itself" in err
    assert (track["dir"] / "track.bvh").read_bytes() == before


def test_track_writes_exports_beside_the_track(tmp_path):
    """``depthtrack track --export``: the track as always, plus OUT/exports/ from the same poses."""
    import pygltflib

    from depthtrack.io.track_output import read_track
    from depthtrack.synth.generate import synthesize_procedural

    seq = tmp_path / "seq"
    synthesize_procedural("wave", seq, seconds=0.12, height=1.7)          # 3 frames
    out = tmp_path / "trk"
    assert main(["track", str(seq), "-o", str(out), "--method", "ep", "--export", "glb,json",
                 "--quiet"]) == 0
    assert sorted(p.name for p in (out / "exports").iterdir()) == ["joints.json", "track.glb"]
    track = read_track(out)
    doc = json.loads((out / "exports" / "joints.json").read_text())
    got = np.array([[doc["frames"][f]["joints"][n] for n in JOINT_NAMES] for f in range(3)], float)
    assert np.allclose(got, track.joints, atol=2e-6)                        # both keep 1 um
    gl = pygltflib.GLTF2().load_binary(str(out / "exports" / "track.glb"))
    assert gl.accessors[gl.animations[0].samplers[0].input].count == 3
