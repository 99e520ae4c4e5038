"""``depthtrack demo``: the tile figure picks the candidate the observation came from; the
whole demo writes every output it names, atomically."""
import json

import numpy as np
import pytest

from depthtrack.body import BodyModel
from depthtrack.camera import Camera
from depthtrack.cli import main
from depthtrack.evaluate import demo


def test_tile_figure_lowest_cost_is_the_observed_candidate(tmp_path):
    body = BodyModel.default(height=1.75)
    rng = np.random.default_rng(5)
    observed, best = demo.write_demo_tiles(tmp_path / "tiles.png", body, Camera.preset("sr4000"), rng)
    assert 1 <= observed < demo.TILE_CANDIDATES
    assert best == observed
    assert (tmp_path / "tiles.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_perturbed_candidates_keep_the_first_and_spread_the_rest():
    pose = np.zeros(48)
    pose[2] = 3.0
    c = demo.perturbed_candidates(pose, 200, np.random.default_rng(0), rotation_std=0.2,
                                  translation_std=0.05)
    assert c.shape == (200, 48)
    np.testing.assert_array_equal(c[0], pose)
    assert np.std(c[1:, 3:]) == pytest.approx(0.2, rel=0.05)
    assert np.std(c[1:, :3] - pose[:3]) == pytest.approx(0.05, rel=0.1)


def test_demo_bad_methods_exit_2_and_write_nothing(tmp_path, capsys):
    assert main(["demo", "--out", str(tmp_path / "out"), "--methods", "hc,nope"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("depthtrack demo: ")
    assert not (tmp_path / "out").exists()


def test_demo_end_to_end_short(tmp_path, capsys):
    out = tmp_path / "demo"
    assert main(["demo", "--out", str(out), "--seconds", "0.4", "--methods", "hc", "--quiet"]) == 0
    printed = capsys.readouterr().out
    for name in (demo.DEMO_MOTION, "tiles.png", "track", "report/report.md", "overlay.mp4"):
        assert (out / name).exists(), name
        assert str(out / name) in printed
    metrics = json.loads((out / "report" / "metrics.json").read_text())
    m = metrics["sequences"][demo.DEMO_MOTION]["hc"]
    assert m["frames"] == 10
    assert 0.0 <= m["within_10cm"] <= 1.0 and m["mean_error_m"] > 0
    assert m["marker_mean_error_m"] is not None
    summary = json.loads((out / "track" / "summary.json").read_text())
    assert summary["method"] == "hc" and summary["frames"] == 10 and summary["seconds"] > 0
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]
