"""C3D marker import with a small file written by ezc3d."""
import json

import numpy as np
import pytest

from depthtrack.camera import Camera
from depthtrack.errors import InputError
from depthtrack.io.c3d import import_c3d_markers, read_c3d_markers
from depthtrack.io.sequence import open_sequence, write_sequence

ezc3d = pytest.importorskip("ezc3d")


def _write_c3d(path, rate=100.0, frames=60, units=None):
    c3d = ezc3d.c3d()
    c3d["parameters"]["POINT"]["RATE"]["value"] = [rate]
    c3d["parameters"]["POINT"]["LABELS"]["value"] = ("LFHD", "RFHD", "C7")
    if units:
        c3d.add_parameter("POINT", "UNITS", [units])
    t = np.arange(frames) / rate
    xyz = np.zeros((3, 3, frames))
    for m in range(3):
        xyz[0, m] = 1000 * (0.1 * m + 0.5 * t)          # mm, moving 0.5 m/s along x
        xyz[1, m] = 1000 * 0.2 * m
        xyz[2, m] = 1000 * 2.0
    xyz[:, 2, 10:20] = np.nan                           # C7 occluded for a while
    points = np.concatenate([xyz, np.ones((1, 3, frames))])
    c3d["data"]["points"] = points
    c3d.write(str(path))


def test_read_c3d(tmp_path):
    path = tmp_path / "trial.c3d"
    _write_c3d(path, units="mm")
    markers = read_c3d_markers(path)
    assert markers.names == ["LFHD", "RFHD", "C7"] and markers.rate == 100.0
    assert markers.units_m == 0.001 and "POINT:UNITS" in markers.units_source
    np.testing.assert_allclose(markers.positions[30, 1], [0.1 + 0.15, 0.2, 2.0], atol=1e-4)
    assert np.isnan(markers.positions[15, 2]).all() and not np.isnan(markers.positions[15, 1]).any()


def test_import_into_sequence(tmp_path):
    c3d_path = tmp_path / "trial.c3d"
    _write_c3d(c3d_path)
    cam = Camera(16, 12, 15.0, 15.0, 8.0, 6.0)
    seq_dir = tmp_path / "seq"
    write_sequence(seq_dir, np.ones((10, 12, 16)), cam, fps=25.0)
    lab_to_camera = np.eye(4)
    lab_to_camera[:3, 3] = [0.0, 0.0, 1.0]
    out = import_c3d_markers(c3d_path, seq_dir, lab_to_camera=lab_to_camera, time_offset=0.02)
    assert out == seq_dir / "groundtruth" / "markers.csv"
    seq = open_sequence(seq_dir)
    assert seq.marker_names == ["LFHD", "RFHD", "C7"]
    # Depth frame k is at mocap time 0.02 + k / 25 s.
    t = 0.02 + np.arange(10) / 25.0
    np.testing.assert_allclose(seq.markers[:, 0, 0], 0.5 * t, atol=1e-4)
    np.testing.assert_allclose(seq.markers[:, 1, 2], 3.0, atol=1e-4)
    # C7 missing between mocap frames 10 and 19: depth frames at 0.10, 0.14, 0.18 s.
    assert np.isnan(seq.markers[[2, 3, 4], 2]).all() and np.isfinite(seq.markers[[0, 1, 5], 2]).all()
    assert json.loads((seq_dir / "sequence.json").read_text())["marker_names"] == seq.marker_names


def test_c3d_errors(tmp_path):
    with pytest.raises(InputError, match="no such C3D"):
        read_c3d_markers(tmp_path / "absent.c3d")
    bad = tmp_path / "bad.c3d"
    bad.write_bytes(b"not a c3d file at all" * 30)
    with pytest.raises(InputError):
        read_c3d_markers(bad)
    good = tmp_path / "trial.c3d"
    _write_c3d(good)
    cam = Camera(16, 12, 15.0, 15.0, 8.0, 6.0)
    write_sequence(tmp_path / "seq", np.ones((3, 12, 16)), cam, fps=25.0)
    with pytest.raises(InputError, match="no marker named 'LASI'"):
        import_c3d_markers(good, tmp_path / "seq", names=["LASI"])
