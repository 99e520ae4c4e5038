"""Synthetic sequences end to end: markers on the rendered surface, ground truth, CLI."""
from pathlib import Path

import numpy as np
import pytest

from depthtrack.body import BodyModel
from depthtrack.contract import JOINT_INDEX as C
from depthtrack.io.sequence import open_sequence
from depthtrack.body.markers import MARKER_NAMES, marker_vertices, vertex_normals
from depthtrack.synth.noise import ToFNoise
from depthtrack.synth.procedural import PROCEDURAL_MOTIONS, procedural_motion
from depthtrack.synth.scene import place_camera, transform_poses

render = pytest.importorskip("depthtrack.render")
DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
WALK = DATA / "motions" / "walk.bvh"


def _gl_or_skip():
    try:
        render.gl_context()
    except render.GLUnavailableError as exc:
        pytest.skip(f"no OpenGL: {exc}")


@pytest.fixture(scope="module")
def body():
    return BodyModel.default(mesh="full")


@pytest.fixture(scope="module")
def mixed_sequence(tmp_path_factory, body):
    _gl_or_skip()
    from depthtrack.synth.generate import synthesize_procedural

    out = tmp_path_factory.mktemp("synth") / "mixed"
    # Kinect v2 resolution: about 1 cm pixels at 3 m, so a wrist is several pixels wide.
    synth = synthesize_procedural("mixed", out, fps=5.0, seconds=8.0, noise="none", body=body,
                                  camera="kinect-v2")
    return out, synth


def test_markers_back_project_onto_rendered_surface(mixed_sequence, body):
    import trimesh

    out, synth = mixed_sequence
    seq = open_sequence(out)
    assert seq.marker_names == list(MARKER_NAMES) and seq.markers.shape == (len(seq), 39, 3)
    # Rebuild the camera-frame poses the generator used (deterministic) for surface normals.
    world = procedural_motion("mixed", body, 5.0, 8.0)
    placement = place_camera(seq.camera, body, world)
    np.testing.assert_allclose(placement.world_to_camera, synth["placement"]["world_to_camera"], atol=1e-5)
    poses = transform_poses(world, placement.world_to_camera)
    vertices = np.asarray(body.posed_vertices(poses))
    idx = marker_vertices(body)
    np.testing.assert_allclose(seq.markers, vertices[:, idx], atol=2e-6)
    checked = 0
    rays = seq.camera.rays()
    for f in range(0, len(seq), 2):
        depth = seq.depth(f)
        mesh = trimesh.Trimesh(vertices[f], body.faces, process=False)
        normals = vertex_normals(vertices[f], body.faces)[idx]
        markers = seq.markers[f]
        view = -markers / np.linalg.norm(markers, axis=1, keepdims=True)
        facing = np.flatnonzero(np.sum(normals * view, axis=1) > 0.5)
        uv = np.rint(seq.camera.project(markers)).astype(int)
        # Independent of the renderer: ray-cast the marker's pixel and its 8 neighbours
        # against the body mesh. The marker must be the first surface hit (no occlusion)
        # and not on the silhouette (all 9 rays hit the body), where one pixel is too coarse.
        origins = np.zeros((9 * len(facing), 3))
        directions = np.concatenate([rays[v - 1:v + 2, u - 1:u + 2].reshape(9, 3) for u, v in uv[facing]])
        hits, ray_index, _ = mesh.ray.intersects_location(origins, directions, multiple_hits=False)
        first = np.full(len(origins), np.inf)
        first[ray_index] = hits[:, 2]
        first = first.reshape(len(facing), 9)
        for k, m in enumerate(facing):
            if not np.all(np.isfinite(first[k])) or first[k, 4] < markers[m, 2] - 0.01:
                continue
            u, v = uv[m]
            z = depth[v, u]
            assert z > 0, MARKER_NAMES[m]
            point = seq.camera.backproject(np.array([z]), uv[m:m + 1].astype(float))[0]
            assert np.linalg.norm(point - markers[m]) < 0.02, (f, MARKER_NAMES[m])
            checked += 1
    assert checked >= 5 * len(range(0, len(seq), 2))   # of the 39 markers, the front ones


def test_sequence_contents_and_metadata(mixed_sequence, body):
    out, synth = mixed_sequence
    seq = open_sequence(out)
    assert len(seq) == 40 and seq.fps == 5.0 and seq.camera.width == 512
    assert seq.subject_height == pytest.approx(body.height, abs=1e-4)
    assert seq.meta["synth"]["noise"] == {"model": "none"}
    assert seq.meta["synth"]["source"] == {"kind": "procedural", "name": "mixed", "start_s": 0.0, "seconds": 8.0}
    # Whole body in view: every joint and marker projects inside the image, in front of the wall.
    for points in (seq.joints, seq.markers):
        uv = seq.camera.project(points)
        assert np.all((uv >= 0) & (uv <= [511, 423]))
    assert np.all(seq.joints[:, C["head"], 1] < seq.joints[:, C["l_ankle"], 1] - 0.8)   # upright, y down
    # A floor and a back wall: the bottom row sees the floor, the top row the wall.
    depth = seq.depth(0)
    assert np.all(depth[-1] > 0) and np.all(depth[0] > 0)
    assert depth[0].min() > seq.joints[0, :, 2].max() + 0.5


def test_cli_bvh_with_noise(tmp_path):
    if not WALK.exists():
        pytest.skip("shared motion data absent")
    _gl_or_skip()
    from depthtrack.cli import main

    out = tmp_path / "walk"
    assert main(["synth", str(WALK), str(out), "--seconds", "0.4", "--camera", "kinect-v2",
                 "--azimuth", "90", "--seed", "3", "--quiet"]) == 0
    seq = open_sequence(out)
    assert len(seq) == 10 and seq.camera.width == 512
    meta = seq.meta["synth"]
    assert meta["noise"] == ToFNoise.for_camera("kinect-v2").to_dict()
    assert meta["source"]["units_m"] == 1.0 and "inferred" in meta["source"]["units_source"]
    assert meta["placement"]["azimuth_deg"] == 90.0 and meta["seed"] == 3
    # Camera at the side: the subject's left-right axis points along the view direction.
    lr = seq.joints[0, C["l_hip"]] - seq.joints[0, C["r_hip"]]
    assert abs(lr[2]) > 0.8 * np.linalg.norm(lr)


def test_cli_errors_are_one_line(tmp_path, capsys):
    from depthtrack.cli import main

    assert main(["synth", str(tmp_path / "absent.bvh"), str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("depthtrack synth: ") and "absent.bvh" in err and "\n" not in err
    assert main(["synth", "--procedural", "wave", "a", "b"]) == 2
    assert main(["synth", "--procedural", "wave", str(tmp_path / "o"), "--seconds", "-1"]) == 2
    assert not (tmp_path / "out").exists() and not (tmp_path / "o").exists()


@pytest.mark.parametrize("name", ["mixed", "squat", "turn", "wave"])   # the benchmark's: test_synth_procedural
def test_procedural_motions_keep_feet_down_and_move(name, body):
    poses = procedural_motion(name, body, fps=10.0)
    assert poses.shape == (int(PROCEDURAL_MOTIONS[name] * 10), 48)
    joints = body.joint_positions(poses)
    rest = body.joint_positions(np.zeros(48))
    lower_ankle = joints[:, [C["l_ankle"], C["r_ankle"]], 1].max(axis=1)
    np.testing.assert_allclose(lower_ankle, rest[C["l_ankle"], 1], atol=1e-9)
    motion = np.linalg.norm(joints - joints[:1], axis=-1).max()
    assert motion > 0.3
    assert np.all(np.diff(poses, axis=0)[:, 3:].max() < 0.5)          # smooth: small steps at 10 fps


def test_camera_sees_a_lying_subject_from_its_side():
    from depthtrack.body.rotations import matrix_to_rotvec, rotation_about
    from depthtrack.synth.scene import initial_heading

    pose = np.zeros((1, 48))
    pose[0, 3:6] = matrix_to_rotvec(rotation_about(np.array([1.0, 0.0, 0.0]), np.radians(-90))[None])[0]
    np.testing.assert_allclose(initial_heading(pose), [1.0, 0.0, 0.0], atol=1e-9)   # supine: its left side
    turned = np.zeros((1, 48))
    turned[0, 3:6] = [0.0, np.pi / 2, 0.0]      # upright, turned 90 degrees about the vertical
    h = initial_heading(turned)
    assert abs(h[1]) < 1e-9 and abs(abs(h[0]) - 1.0) < 1e-9
