"""Body shape: joints and surface follow the shape, JSON round trips, random people, synth --shape."""
import json

import numpy as np
import pytest

from depthtrack.body import BodyModel
from depthtrack.body.shape import (SHAPE_FIELDS, SHAPE_RANGES, BodyShape, random_person,
                                   random_shape)
from depthtrack.body.skeleton import DOF, JOINT_ID
from depthtrack.contract import JOINT_INDEX as C
from depthtrack.errors import InputError

render = pytest.importorskip("depthtrack.render")


@pytest.fixture(scope="module")
def body():
    return BodyModel.default(1.75, mesh="decimated")


def _gl_or_skip():
    try:
        render.gl_context()
    except render.GLUnavailableError as exc:
        pytest.skip(f"no OpenGL: {exc}")


def test_average_shape_changes_nothing(body):
    same = body.shaped(BodyShape())
    np.testing.assert_allclose(same.offsets, body.offsets, atol=1e-12)
    np.testing.assert_allclose(same.rest_vertices, body.rest_vertices, atol=1e-9)
    assert body.shape.is_average


def test_longer_thighs_lower_the_feet_by_the_thigh_growth(body):
    """Thigh x 1.1 at a kept scale: the ankles move 10 % of the thigh's vertical extent
    further below the pelvis (the standing pelvis rises by that much), the arms stay."""
    long = body.shaped(BodyShape(thigh=1.1))
    zero = np.zeros(DOF)
    j0, j1 = body.joint_positions(zero), long.joint_positions(zero)
    thigh_drop = body.offsets[JOINT_ID["l_knee"], 1]          # hip-to-knee, downwards (+y)
    assert thigh_drop > 0.4
    for ankle in ("l_ankle", "r_ankle"):
        assert j1[C[ankle], 1] - j0[C[ankle], 1] == pytest.approx(0.1 * thigh_drop, abs=1e-9)
    np.testing.assert_allclose(j1[C["l_wrist"]], j0[C["l_wrist"]], atol=1e-12)
    assert long.height - body.height == pytest.approx(0.1 * thigh_drop, abs=1e-3)
    # the surface follows: the lowest vertex (the sole) drops by the same amount
    drop = long.rest_vertices[:, 1].max() - body.rest_vertices[:, 1].max()
    assert drop == pytest.approx(0.1 * thigh_drop, abs=2e-3)
    # posed too: with the knee bent, the knee is 10 % further from the hip
    bent = zero.copy()
    bent[3 + 3 * JOINT_ID["l_hip"]] = -1.2
    pa, pb = body.joint_positions(bent), long.joint_positions(bent)
    la = np.linalg.norm(pa[C["l_knee"]] - pa[C["l_hip"]])
    lb = np.linalg.norm(pb[C["l_knee"]] - pb[C["l_hip"]])
    assert lb / la == pytest.approx(1.1, abs=1e-9)


def test_shape_at_a_given_height_keeps_the_height():
    shaped = BodyModel.default(1.68, mesh="decimated", shape=BodyShape(thigh=1.1, torso=0.92))
    assert shaped.height == pytest.approx(1.68, abs=1e-9)
    assert shaped.with_mesh("full").height == pytest.approx(1.68, abs=1e-9)
    assert shaped.with_mesh("full").shape == shaped.shape


def test_widths_and_girth_change_lengths_as_documented(body):
    base = body.segment_lengths()
    wide = body.shaped(BodyShape(shoulder_width=1.1, hip_width=1.1)).segment_lengths()
    assert wide["shoulder_width"] / base["shoulder_width"] == pytest.approx(1.1, rel=2e-4)
    assert wide["hip_width"] / base["hip_width"] == pytest.approx(1.1, rel=2e-4)
    for k in ("upper_arm", "thigh", "shin", "neck_head"):
        assert wide[k] == pytest.approx(base[k], abs=1e-5)
    # limb girth widens the limbs about their axis, not their length
    girth = body.shaped(BodyShape(limb_girth=1.25))
    assert girth.segment_lengths()["thigh"] == pytest.approx(base["thigh"], abs=1e-5)
    thigh = (body.mesh.dominant_joint() == JOINT_ID["l_hip"])
    knee = body.joint_positions(np.zeros(DOF))[C["l_knee"]]
    hip = body.joint_positions(np.zeros(DOF))[C["l_hip"]]
    axis = (knee - hip) / np.linalg.norm(knee - hip)

    def radius(b):
        v = b.rest_vertices[thigh] - hip
        return np.median(np.linalg.norm(v - np.outer(v @ axis, axis), axis=1))

    assert radius(girth) / radius(body) == pytest.approx(1.25, rel=0.03)


def test_girth_widens_the_rendered_silhouette(body):
    _gl_or_skip()
    from depthtrack.camera import Camera

    cam = Camera.preset("kinect-v2")
    pose = body.default_pose((0.0, 0.0, 3.0))
    wide = body.shaped(BodyShape(torso_girth=1.3))
    r = render.FrameRenderer(cam)
    try:
        a, b = r.render(body, pose) > 0, r.render(wide, pose) > 0
    finally:
        r.release()
    u, v = np.rint(cam.project(body.joint_positions(pose)[C["pelvis"]][None])[0]).astype(int)

    def trunk_width(mask, row):
        """Run of body pixels through the pelvis column (the arms beside it not counted)."""
        line = mask[row]
        left = u - np.argmin(line[u::-1])
        right = u + np.argmin(line[u:])
        return right - left

    for row in (v - 20, v - 35):                             # waist and chest
        assert trunk_width(b, row) / trunk_width(a, row) == pytest.approx(1.3, abs=0.06)
    assert b.sum() > a.sum() * 1.1


def test_json_round_trip(tmp_path):
    shape = BodyShape(upper_arm=1.05, forearm=0.96, thigh=1.08, torso=0.94, limb_girth=1.2)
    assert BodyShape.from_json(shape.to_json()) == shape
    body = BodyModel.default(1.81, shape=shape)
    path = tmp_path / "body.json"
    path.write_text(body.to_json())
    back = BodyModel.from_json(path)
    assert back.shape == shape
    assert back.height == pytest.approx(1.81, abs=1e-6)
    np.testing.assert_allclose(back.offsets, body.offsets, atol=1e-9)
    pose = body.default_pose((0.1, 0.0, 3.0))
    np.testing.assert_allclose(back.posed_vertices(pose), body.posed_vertices(pose), atol=1e-9)
    data = json.loads(path.read_text())
    assert data["segment_lengths_m"]["thigh"] == pytest.approx(body.segment_lengths()["thigh"])
    assert BodyShape.from_json(path) == shape                   # the shape block of a body.json
    import depthtrack
    assert depthtrack.BodyModel.from_json(str(path)).shape == shape


def test_bad_shape_json_is_an_input_error(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text('{"thigh": 1.1, "tail": 2}')
    with pytest.raises(InputError, match="tail"):
        BodyShape.from_json(bad)
    bad.write_text('{"thigh": -1}')
    with pytest.raises(InputError, match="positive"):
        BodyShape.from_json(bad)
    bad.write_text('{"format": "something/1"}')
    with pytest.raises(InputError, match="not a body file"):
        BodyModel.from_json(bad)


def test_random_people_are_reproducible_plausible_and_correlated():
    assert random_person(5) == random_person(5)
    assert random_person(5) != random_person(6)
    people = [random_person(s) for s in range(300)]
    heights = np.array([h for h, _ in people])
    assert 1.50 <= heights.min() and heights.max() <= 2.00 and heights.std() > 0.05
    for _, shape in people:
        assert shape.out_of_range() == []
    rng = np.random.default_rng(0)
    logs = np.log([random_shape(rng).as_array() for _ in range(2000)])
    i = {f: k for k, f in enumerate(SHAPE_FIELDS)}
    corr = np.corrcoef(logs.T)
    assert corr[i["thigh"], i["shin"]] == pytest.approx(0.5, abs=0.08)
    assert corr[i["limb_girth"], i["torso_girth"]] == pytest.approx(0.7, abs=0.08)
    assert corr[i["thigh"], i["torso"]] < -0.2
    assert set(SHAPE_RANGES) == set(SHAPE_FIELDS)


def test_synth_shape_random_is_reproducible_and_recorded(tmp_path, capsys):
    _gl_or_skip()
    from depthtrack.cli import main
    from depthtrack.io.sequence import open_sequence

    outs = []
    for name in ("a", "b"):
        out = tmp_path / name
        code = main(["synth", "--procedural", "wave", str(out), "--seconds", "0.2", "--fps", "10",
                     "--shape", "random", "--shape-seed", "4", "--clothing", "loose", "--quiet"])
        assert code == 0
        outs.append(out)
    meta = [json.loads((o / "sequence.json").read_text()) for o in outs]
    assert meta[0]["synth"]["shape"] == meta[1]["synth"]["shape"]
    a, b = open_sequence(outs[0]), open_sequence(outs[1])
    np.testing.assert_array_equal(a.depth(1), b.depth(1))
    shape = meta[0]["synth"]["shape"]
    height, truth = random_person(4)
    assert shape["source"] == "random" and shape["seed"] == 4
    assert BodyShape.from_dict(shape["scales"]) == BodyShape.from_dict(truth.to_dict())
    assert meta[0]["subject"]["height_m"] == pytest.approx(height, abs=1e-3)
    assert shape["clothing"]["kind"] == "loose"
    # the ground-truth joints are the shaped body's: thigh length as recorded
    j = a.joints[0]
    thigh = np.linalg.norm(j[C["l_knee"]] - j[C["l_hip"]])
    assert thigh == pytest.approx(shape["segment_lengths_m"]["thigh"], abs=2e-3)
    # a shape file; a bad one fails with one line and writes nothing
    f = tmp_path / "me.json"
    f.write_text('{"thigh": 1.08, "torso_girth": 1.2}')
    assert main(["synth", "--procedural", "wave", str(tmp_path / "c"), "--seconds", "0.1",
                 "--shape", str(f), "--quiet"]) == 0
    meta_c = json.loads((tmp_path / "c" / "sequence.json").read_text())
    assert meta_c["synth"]["shape"]["scales"]["thigh"] == 1.08
    assert meta_c["subject"]["height_m"] == pytest.approx(1.75, abs=1e-4)
    f.write_text('{"thighs": 1.08}')
    assert main(["synth", "--procedural", "wave", str(tmp_path / "d"), "--shape", str(f), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert "thighs" in err and str(f) in err and "\n" not in err
    assert not (tmp_path / "d").exists()


def test_loose_clothing_stands_off_trunk_and_legs_only(body):
    from depthtrack.synth.subject import clothing_offsets

    full = BodyModel.default(1.75)
    off = clothing_offsets(full.mesh, "loose", seed=1)
    dom = full.mesh.dominant_joint()
    legs = np.isin(dom, [JOINT_ID[j] for j in ("l_hip", "r_hip", "pelvis")])
    arms = np.isin(dom, [JOINT_ID[j] for j in ("l_elbow", "r_elbow", "l_wrist", "r_wrist")])
    assert 0.01 <= np.median(off[legs]) <= 0.04 and off.max() <= 0.0401
    assert np.all(off[arms] < 1e-3)
    assert np.all(clothing_offsets(full.mesh, "none") == 0)
