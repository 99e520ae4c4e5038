"""Azure Kinect .mkv: the shared one-frame NFOV recording (skipped without ../shared/data)."""
import json

import numpy as np
import pytest

from depthtrack.cli import main
from depthtrack.io.mkv import DEPTH_MODES, mode_intrinsics
from depthtrack.io.registry import open_sequence


@pytest.fixture(scope="module")
def mkv(shared_data):
    path = shared_data / "recordings" / "azure_kinect_nfov_1frame.mkv"
    if not path.is_file():
        pytest.skip("recordings/azure_kinect_nfov_1frame.mkv is not in ../shared/data")
    return path


def _direct(path):
    """The DEPTH track decoded by PyAV itself, and the calibration attachment's JSON."""
    import av

    with av.open(str(path)) as container:
        stream = next(s for s in container.streams.video if s.metadata.get("title") == "DEPTH")
        frames = [(f.pts, f.to_ndarray()) for f in container.decode(stream)]
        cal = next(json.loads(bytes(s.data)) for s in container.streams
                   if s.type == "attachment" and s.metadata.get("filename") == "calibration.json")
        mode = stream.metadata["K4A_DEPTH_MODE"]
    return frames, cal, mode


def test_nfov_frame_and_intrinsics(mkv):
    frames, cal, mode = _direct(mkv)
    assert mode == "NFOV_UNBINNED" and len(frames) == 1
    seq = open_sequence(mkv)
    assert seq.reader == "azure-kinect-mkv" and len(seq) == 1
    raw = seq.raw_depth(0)
    assert raw.dtype == np.uint16 and raw.shape == (576, 640)
    assert np.array_equal(raw, frames[0][1])            # equal to PyAV's own decode
    assert seq.depth_scale == 0.001 and 0.5 < np.median(seq.depth(0)[raw > 0]) < 4.0
    assert seq.timestamps[0] == pytest.approx(frames[0][0] * 1e-6)
    # Expected intrinsics straight from the attachment: the depth camera's normalised
    # (cx, cy, fx, fy) on the 1024 x 1024 sensor; NFOV unbinned is the sensor window from
    # column 192, row 180 (the Azure Kinect SDK's table: not centred vertically), and OpenCV
    # puts (0, 0) at the centre of the first pixel.
    depth_cam = next(c for c in cal["CalibrationInformation"]["Cameras"]
                     if c["Location"] == "CALIBRATION_CameraLocationD0")
    cx_n, cy_n, fx_n, fy_n = depth_cam["Intrinsics"]["ModelParameters"][:4]
    expected = (fx_n * 1024, fy_n * 1024, cx_n * 1024 - 192 - 0.5, cy_n * 1024 - 180 - 0.5)
    got = (seq.camera.fx, seq.camera.fy, seq.camera.cx, seq.camera.cy)
    assert np.abs(np.subtract(got, expected)).max() < 1.0
    assert seq.meta["source"]["undistorted"] is False


def test_convert_mkv_to_sequence(mkv, tmp_path):
    frames, _, _ = _direct(mkv)
    out = tmp_path / "kinect"
    assert main(["convert", str(mkv), str(out), "--quiet"]) == 0
    back = open_sequence(out)
    assert back.camera.shape == (576, 640) and np.array_equal(back.raw_depth(0), frames[0][1])
    meta = json.loads((out / "sequence.json").read_text())
    assert meta["source"]["depth_mode"] == "NFOV_UNBINNED" and meta["source"]["reader"] == "azure-kinect-mkv"


def test_undistort_moves_pixels_by_the_calibration(mkv):
    plain = open_sequence(mkv)
    und = open_sequence(mkv, undistort=True)
    assert und.camera == plain.camera and und.meta["source"]["undistorted"] is True
    a, b = plain.raw_depth(0), und.raw_depth(0)
    # Nearest-neighbour resampling: every value comes from the recording, none is blended.
    assert np.isin(np.unique(b), np.unique(a)).all()
    # Near the principal point the lens barely moves pixels; towards the edges it does.
    cx, cy = int(round(plain.camera.cx)), int(round(plain.camera.cy))
    assert np.mean(a[cy - 10:cy + 10, cx - 10:cx + 10] == b[cy - 10:cy + 10, cx - 10:cx + 10]) > 0.8
    assert np.mean(a[a > 0] != b[a > 0]) > 0.3


def test_binned_modes_scale_the_unbinned_camera():
    params = np.array([0.51, 0.52, 0.49, 0.493] + [0.0] * 10)
    full, _ = mode_intrinsics(params, "NFOV_UNBINNED")
    half, _ = mode_intrinsics(params, "NFOV_2X2BINNED")
    assert (half.width, half.height) == (320, 288)
    assert half.fx == pytest.approx(full.fx / 2) and half.cx == pytest.approx((full.cx + 0.5) / 2 - 0.5)
    wide, _ = mode_intrinsics(params, "WFOV_UNBINNED")
    assert (wide.width, wide.height) == DEPTH_MODES["WFOV_UNBINNED"][2]
    assert wide.cx == pytest.approx(full.cx + 192) and wide.cy == pytest.approx(full.cy + 180)


# ------------------------------------------------ written recordings (no shared data needed)
def test_many_frames_in_any_order(tmp_path):
    from k4a_writer import calibration_json, write_k4a_mkv

    rng = np.random.default_rng(3)
    frames = rng.integers(0, 5000, (20, 288, 320)).astype(np.uint16)
    path = write_k4a_mkv(tmp_path / "binned.mkv", frames, "NFOV_2X2BINNED",
                         calibration_json([0.51, 0.52, 0.49, 0.493] + [0.0] * 10))
    seq = open_sequence(path)
    assert len(seq) == 20 and seq.camera.shape == (288, 320)
    assert seq.fps == pytest.approx(30.0, rel=0.02)          # from the frame times (ms clock)
    assert np.all(np.diff(seq.timestamps) > 0)
    # Sequential, backwards and jumping across read batches: always the right frame.
    for i in list(range(20)) + [19, 3, 17, 0, 16, 15]:
        assert np.array_equal(seq.raw_depth(i), frames[i]), i


def test_wide_fov_is_undistorted_onto_the_pinhole_camera(tmp_path):
    import cv2

    from k4a_writer import calibration_json, write_k4a_mkv

    # Strong radial distortion (rational model, as a WFOV lens) and a little tangential.
    params = [0.5, 0.505, 0.245, 0.246, 0.4, -0.05, 0.0, 0.75, 0.05, 0.0, 0, 0, 2e-4, -1e-4]
    h = w = 512
    # Each pixel's value tells where it was (1 + index mod 60000), so resampling can be traced.
    source = (1 + np.arange(h * w) % 60000).reshape(1, h, w).astype(np.uint16)
    path = write_k4a_mkv(tmp_path / "wide.mkv", source, "WFOV_2X2BINNED", calibration_json(params))
    seq = open_sequence(path)
    assert seq.meta["source"]["undistorted"] is True               # auto: WFOV
    cam = seq.camera
    assert (cam.fx, cam.cx) == pytest.approx((0.245 * 512, 0.5 * 512 - 0.5))
    out = seq.raw_depth(0)
    # Independently: project the ray of output pixel (u, v) through the lens model
    # (OpenCV order k1, k2, p1, p2, k3..k6; the calibration stores ... p2, p1).
    k1, k2, k3, k4, k5, k6, _, _, p2, p1 = params[4:]
    dist = np.array([k1, k2, p1, p2, k3, k4, k5, k6])
    uv = np.array([[256, 256], [100, 120], [400, 300], [60, 450]], float)
    rays = np.c_[(uv[:, 0] - cam.cx) / cam.fx, (uv[:, 1] - cam.cy) / cam.fy, np.ones(len(uv))]
    src, _ = cv2.projectPoints(rays, np.zeros(3), np.zeros(3), cam.matrix, dist)
    src = src.reshape(-1, 2)
    for (u, v), (su, sv) in zip(uv.astype(int), src):
        # The pixels that hold this value (it repeats every 60000): one is where it came from.
        rows, cols = np.divmod(np.flatnonzero(source[0].ravel() == out[v, u]), w)
        assert np.min(np.hypot(cols - su, rows - sv)) <= 1.0, (u, v)
    assert not np.array_equal(out, source[0])
    # Forced off: the frame as recorded.
    assert np.array_equal(open_sequence(path, undistort=False).raw_depth(0), source[0])
