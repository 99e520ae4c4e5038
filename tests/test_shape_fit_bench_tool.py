"""tools/shape_fit_bench.py --tracked: the oracle body is the person's, and the summary's numbers."""

import numpy as np
import pytest
from tool_module import load_tool


@pytest.fixture(scope="module")
def tool():
    return load_tool("shape_fit_bench")


def test_true_body_is_the_synthesized_person(tool, tmp_path):
    from depthtrack import render
    from depthtrack.body import BodyModel
    from depthtrack.io.sequence import open_sequence
    from depthtrack.synth.generate import synthesize
    from depthtrack.synth.subject import make_subject

    try:
        render.gl_context()
    except render.GLUnavailableError as exc:
        pytest.skip(f"no OpenGL: {exc}")
    person, info = make_subject(None, "random", 5, "loose", mesh="decimated")
    synthesize(tmp_path / "seq", person, person.default_pose()[None], 10.0, camera="kinect-v2",
               noise="none", subject=info)
    body = tool.true_body(open_sequence(tmp_path / "seq"))
    truth, template = info["segment_lengths_m"], BodyModel.default(height=info["height_m"]).segment_lengths()
    got = body.segment_lengths()
    assert abs(body.height - info["height_m"]) < 1e-3
    assert max(abs(got[s] - truth[s]) for s in truth) < 1e-3
    # the person is not the template: some segment differs by more than a centimetre
    assert max(abs(template[s] - truth[s]) for s in truth) > 0.01
    assert body.mesh_name == "full"                      # no clothing: the tracker's own skin


def test_summary_mean_sd_and_median_segment_error(tool):
    rows = [{"template": {"within_10cm": w, "segment_errors_m": {"thigh": e, "shin": -e}}}
            for w, e in ((0.9, 0.01), (0.8, -0.03), (1.0, 0.02))]
    out = tool.summarise_tracked(rows, ["template"])["template"]
    assert out["within_10cm_mean"] == pytest.approx(0.9)
    assert out["within_10cm_sd"] == pytest.approx(0.1)
    assert out["segment_error_median_m"] == pytest.approx(0.02)
    assert tool.BODIES == ("average", "template", "fitted", "oracle")
    assert np.isfinite(out["within_10cm_sd"])
