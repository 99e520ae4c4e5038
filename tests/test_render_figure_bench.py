"""The tiles figure and the bench report: files and fields, not timings."""
import json

import numpy as np
import pytest

from depthtrack.errors import InputError
from depthtrack.render.tiles_figure import write_tiles_figure


def test_tiles_figure_is_a_png_with_the_best_tile_framed_in_green(tmp_path):
    import matplotlib.image

    rng = np.random.default_rng(0)
    depths = np.zeros((5, 32, 32), np.float32)
    depths[:, 8:24, 10:22] = rng.uniform(2.0, 3.0, (5, 1, 1))
    observed = depths[2].copy()
    observed[observed == 0] = np.inf
    path = tmp_path / "tiles.png"
    write_tiles_figure(path, depths, np.array([0.3, 0.2, 0.01, 0.5, 0.4]), observed, title="t")
    image = matplotlib.image.imread(path)
    assert image.ndim == 3 and image.shape[0] > 100 and image.shape[1] > 100
    green = (image[..., 1] > 0.7) & (image[..., 0] < 0.5) & (image[..., 2] < 0.3)
    assert green.sum() > 100          # the limegreen frame around the best tile
    assert not list(tmp_path.glob(".*tmp"))   # written atomically, nothing left behind


def test_tiles_figure_rejects_mismatched_shapes(tmp_path):
    with pytest.raises(InputError):
        write_tiles_figure(tmp_path / "x.png", np.zeros((3, 8, 8)), np.zeros(2), np.zeros((8, 8)))


def test_bench_json_reports_every_cell_and_the_mesh_size(capsys):
    from depthtrack.body import BodyModel
    from depthtrack.cli import main

    assert main(["bench", "--json", "--tiles", "16", "32", "--batches", "2", "5",
                 "--seconds", "0.01", "--quiet"]) == 0
    report = json.loads(capsys.readouterr().out)
    body = BodyModel.default(mesh="decimated")
    assert report["mesh"] == {"name": "decimated", "vertices": len(body.mesh.vertices),
                              "triangles": len(body.faces)}
    assert sorted((r["tile"], r["batch"]) for r in report["results"]) == \
        [(16, 2), (16, 5), (32, 2), (32, 5)]
    assert all(r["candidates_per_s"] > 0 for r in report["results"])
    assert report["gl_renderer"]
    assert [b["tile"] for b in report["breakdown"]] == [16, 32]
    assert all(0 <= b["geometry_cpu_ms"] and b["render_cpu_ms"] > 0 for b in report["breakdown"])


def test_bench_rejects_a_tile_that_is_not_a_power_of_two(capsys):
    from depthtrack.cli import main

    assert main(["bench", "--tiles", "48"]) == 2
    assert "power of two" in capsys.readouterr().err
