"""The shape fit recovers a known body shape from noise-free depth frames."""
import json

import numpy as np
import pytest

from depthtrack.body import BodyModel
from depthtrack.body.shape import BodyShape
from depthtrack.camera import Camera
from depthtrack.synth.procedural import procedural_motion

render = pytest.importorskip("depthtrack.render")

TRUTH = BodyShape(upper_arm=1.06, forearm=0.95, thigh=1.07, shin=0.95, torso=0.95, neck_head=1.05,
                  shoulder_width=1.08, hip_width=1.1, foot=1.0, limb_girth=1.15, torso_girth=1.1)


def test_shape_fit_recovers_segment_lengths(tmp_path):
    try:
        render.gl_context()
    except render.GLUnavailableError as exc:
        pytest.skip(f"no OpenGL: {exc}")
    from depthtrack.track.shape_fit import fit_shape, write_body_json

    camera = Camera.preset("sr4000")
    truth = BodyModel.default(1.75, shape=TRUTH)
    template = BodyModel.default(1.75)
    # bent elbows and knees tell the segments apart: two frames of the wave, two of the squat
    wave = procedural_motion("wave", template, 25.0)
    squat = procedural_motion("squat", template, 25.0)
    poses = np.stack([wave[25], wave[60], squat[50], squat[90]])
    poses[:, 2] += 4.6                    # 4.6 m away: the whole person fits a 128-pixel tile
    r = render.FrameRenderer(camera)
    try:
        depths = [r.render(truth, p) for p in poses]
    finally:
        r.release()
    masks = [d > 0 for d in depths]
    # exact frames and poses: a weak prior. The default (30, chosen on noisy tracked dev
    # sequences) pulls this person, about 2 s.d. from the average in several fields, up to
    # 2 cm toward the template.
    fit = fit_shape(template, camera, depths, masks, poses, tile=128, rounds=1, prior_weight=1.0)
    want, got, before = truth.segment_lengths(), fit.body.segment_lengths(), template.segment_lengths()
    errors = {k: got[k] - want[k] for k in want}
    assert max(abs(e) for e in errors.values()) < 0.02, errors
    # the template was off by several centimetres where the shape differs most
    assert abs(before["shoulder_width"] - want["shoulder_width"]) > 0.05
    assert abs(before["hip_width"] - want["hip_width"]) > 0.03
    assert fit.height_m == pytest.approx(truth.height, abs=0.02)
    assert fit.energy < fit.start_energy
    # body.json rebuilds the fitted body
    write_body_json(tmp_path / "body.json", fit.body, fit)
    data = json.loads((tmp_path / "body.json").read_text())
    assert data["fit"]["frames"] == 4
    back = BodyModel.from_json(tmp_path / "body.json")
    np.testing.assert_allclose(back.offsets, fit.body.offsets, atol=1e-9)
