"""Depth sequence contract: write, read, rewrite; lazy frames; every validation error."""
import filecmp
import json
import shutil

import cv2
import numpy as np
import pytest

from depthtrack.camera import Camera
from depthtrack.contract import JOINT_NAMES
from depthtrack.errors import InputError
from depthtrack.io.sequence import open_sequence, png_header, write_sequence

CAMERA = Camera(width=32, height=24, fx=30.0, fy=30.0, cx=16.0, cy=12.0)
F = 5


def _example(rng=None):
    rng = rng or np.random.default_rng(0)
    depths = rng.uniform(0.5, 4.0, (F, CAMERA.height, CAMERA.width))
    depths[:, :3, :4] = 0.0          # no reading
    depths[1, 5, 5] = np.nan         # non-finite: stored as no reading
    joints = rng.normal(0, 0.5, (F, 15, 3)) + [0, 0, 2.5]
    joints[2, 4] = np.nan            # unknown joint in one frame
    markers = rng.normal(0, 0.5, (F, 3, 3)) + [0, 0, 2.5]
    markers[0, 1] = np.nan           # marker missing in the first frame
    return depths, joints, markers, ["LFHD", "RFHD", "C7"]


def _write_example(path, **kw):
    depths, joints, markers, names = _example()
    args = dict(joints=joints, markers=markers, marker_names=names, subject=1.8,
                extra={"synth": {"noise": {"model": "none"}}})
    args.update(kw)
    write_sequence(path, depths, CAMERA, 25.0, **args)
    return depths, joints, markers, names


def _rewrite(seq, path):
    extra = {k: v for k, v in seq.meta.items()
             if k not in ("format", "fps", "depth_scale", "camera", "subject")}
    write_sequence(path, iter(seq), seq.camera, seq.fps, seq.depth_scale, joints=seq.joints,
                   markers=seq.markers, marker_names=seq.marker_names,
                   subject=seq.meta.get("subject"), extra=extra)


@pytest.mark.parametrize("suffix", ["", ".npz"])
def test_write_read_rewrite_unchanged(tmp_path, suffix):
    path = tmp_path / f"seq{suffix}"
    depths, joints, markers, names = _write_example(path)
    seq = open_sequence(path)
    assert len(seq) == F and seq.fps == 25.0 and seq.depth_scale == 0.001
    assert seq.camera == CAMERA and seq.subject_height == 1.8
    assert seq.meta["synth"] == {"noise": {"model": "none"}}
    expected = np.where(np.isfinite(depths), np.rint(np.nan_to_num(depths) / 0.001) * 0.001, 0.0)
    for i, depth in enumerate(seq):
        assert depth.dtype == np.float32 and depth.shape == (24, 32)
        np.testing.assert_allclose(depth, expected[i], atol=1e-6)
    np.testing.assert_allclose(seq.joints, joints, atol=1e-6)
    assert np.isnan(seq.joints[2, 4]).all() and seq.marker_names == names
    np.testing.assert_allclose(seq.markers, markers, atol=1e-6)

    again = tmp_path / f"again{suffix}"
    _rewrite(seq, again)
    seq2 = open_sequence(again)
    for i in range(F):
        np.testing.assert_array_equal(seq2.raw_depth(i), seq.raw_depth(i))
    np.testing.assert_array_equal(seq2.joints, seq.joints)
    np.testing.assert_array_equal(seq2.markers, seq.markers)
    assert seq2.meta == seq.meta
    if not suffix:
        for name in ("sequence.json", "groundtruth/joints.csv", "groundtruth/markers.csv"):
            assert filecmp.cmp(path / name, again / name, shallow=False), name


def test_directory_layout_and_png_format(tmp_path):
    path = tmp_path / "seq"
    _write_example(path)
    assert sorted(p.name for p in (path / "depth").iterdir()) == [f"{i:06d}.png" for i in range(F)]
    raw = cv2.imread(str(path / "depth" / "000000.png"), cv2.IMREAD_UNCHANGED)
    assert raw.dtype == np.uint16 and raw.shape == (24, 32)
    assert png_header(path / "depth" / "000000.png") == (32, 24, 16, 0)
    meta = json.loads((path / "sequence.json").read_text())
    assert meta["format"] == "depthtrack-sequence/1" and meta["camera"]["fx"] == 30.0
    lines = (path / "groundtruth" / "joints.csv").read_text().splitlines()
    assert lines[0] == "frame,joint,x,y,z"
    assert len(lines) == 1 + F * 15 - 1      # the unknown joint has no row
    assert {l.split(",")[1] for l in lines[1:]} == set(JOINT_NAMES)


def test_iterable_input_and_no_ground_truth(tmp_path):
    path = tmp_path / "seq"
    write_sequence(path, (np.full(CAMERA.shape, 1.5) for _ in range(3)), CAMERA, 30)
    seq = open_sequence(path)
    assert len(seq) == 3 and seq.joints is None and seq.markers is None and seq.subject_height is None
    assert np.all(seq.depth(2) == np.float32(1.5))


def test_failed_write_leaves_nothing(tmp_path):
    path = tmp_path / "seq"

    def frames():
        yield np.ones(CAMERA.shape)
        raise RuntimeError("camera unplugged")

    with pytest.raises(RuntimeError):
        write_sequence(path, frames(), CAMERA, 25)
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(ValueError, match="16-bit range"):
        write_sequence(path, [np.full(CAMERA.shape, 70.0)], CAMERA, 25)
    assert list(tmp_path.iterdir()) == []


def _break(path, how):
    """Damage a written sequence directory in one way; return the file expected in the message."""
    depth = path / "depth"
    if how == "no json":
        (path / "sequence.json").unlink()
        return path / "sequence.json", "missing sequence.json"
    if how == "bad json":
        (path / "sequence.json").write_text("{\"format\": ")
        return path / "sequence.json", "invalid JSON"
    if how == "version":
        meta = json.loads((path / "sequence.json").read_text())
        meta["format"] = "depthtrack-sequence/9"
        (path / "sequence.json").write_text(json.dumps(meta))
        return path / "sequence.json", "unknown format version"
    if how == "fps":
        meta = json.loads((path / "sequence.json").read_text())
        meta["fps"] = float("nan")
        (path / "sequence.json").write_text(json.dumps(meta))
        return path / "sequence.json", "fps"
    if how == "8-bit":
        cv2.imwrite(str(depth / "000003.png"), np.zeros((24, 32), np.uint8))
        return depth / "000003.png", "not 16-bit single channel"
    if how == "rgb":
        cv2.imwrite(str(depth / "000003.png"), np.zeros((24, 32, 3), np.uint16))
        return depth / "000003.png", "not 16-bit single channel"
    if how == "size":
        cv2.imwrite(str(depth / "000004.png"), np.zeros((24, 31), np.uint16))
        return depth / "000004.png", "31 x 24"
    if how == "not png":
        (depth / "000001.png").write_bytes(b"hello")
        return depth / "000001.png", "not a PNG"
    if how == "gap":
        (depth / "000002.png").unlink()
        return depth, "gap in frame numbering: frame 2"
    if how == "empty":
        shutil.rmtree(depth)
        depth.mkdir()
        return depth, "empty sequence"
    if how == "joint name":
        csv = path / "groundtruth" / "joints.csv"
        csv.write_text(csv.read_text().replace(",l_knee,", ",left_knee,", 1))
        return csv, "unknown joint name 'left_knee'"
    if how == "joint nan":
        csv = path / "groundtruth" / "joints.csv"
        lines = csv.read_text().splitlines()
        lines[3] = ",".join(lines[3].split(",")[:2] + ["nan", "0", "1"])
        csv.write_text("\n".join(lines) + "\n")
        return csv, "line 4: non-finite"
    if how == "marker inf":
        csv = path / "groundtruth" / "markers.csv"
        lines = csv.read_text().splitlines()
        lines[2] = ",".join(lines[2].split(",")[:2] + ["inf", "0", "1"])
        csv.write_text("\n".join(lines) + "\n")
        return csv, "line 3: non-finite"
    if how == "frame range":
        csv = path / "groundtruth" / "joints.csv"
        csv.write_text(csv.read_text() + f"{F},head,0,0,1\n")
        return csv, "beyond the sequence"
    raise AssertionError(how)


CASES = ["no json", "bad json", "version", "fps", "8-bit", "rgb", "size", "not png", "gap", "empty",
         "joint name", "joint nan", "marker inf", "frame range"]


@pytest.mark.parametrize("how", CASES)
def test_validation_errors_name_file_and_problem(tmp_path, how):
    path = tmp_path / "seq"
    _write_example(path)
    culprit, message = _break(path, how)
    with pytest.raises(InputError) as info:
        seq = open_sequence(path)
        seq.joints, seq.markers  # ground truth is parsed on first use
    text = str(info.value)
    assert str(culprit) in text and message in text and "\n" not in text


def test_npz_validation(tmp_path):
    path = tmp_path / "seq.npz"
    _write_example(path)
    with np.load(path) as data:
        arrays = dict(data)
    bad = tmp_path / "bad.npz"
    np.savez(bad, **{**arrays, "depth": arrays["depth"][:, :, :-1]})
    with pytest.raises(InputError, match="camera is 32 x 24"):
        open_sequence(bad)
    np.savez(bad, **{**arrays, "depth": arrays["depth"][:0]})
    with pytest.raises(InputError, match="empty sequence"):
        open_sequence(bad)
    np.savez(bad, **{**arrays, "depth": arrays["depth"].astype(np.float32)})
    with pytest.raises(InputError, match="uint16"):
        open_sequence(bad)
    with pytest.raises(InputError, match="no such"):
        open_sequence(tmp_path / "absent.npz")
    with pytest.raises(InputError, match="no such"):
        open_sequence(tmp_path / "absent")


def test_frames_load_lazily(tmp_path):
    path = tmp_path / "seq"
    _write_example(path)
    seq = open_sequence(path)
    # Corrupt the pixels (not the header) of one frame after opening: only reading it fails.
    data = bytearray((path / "depth" / "000002.png").read_bytes())
    data[40:] = b"\0" * (len(data) - 40)
    (path / "depth" / "000002.png").write_bytes(bytes(data))
    seq.depth(0)
    seq.depth(4)
    with pytest.raises(InputError):
        seq.depth(2)


@pytest.mark.parametrize("name", ["seq", "seq.npz"])
def test_writing_no_frames_is_refused(tmp_path, name):
    with pytest.raises(ValueError, match="empty sequence"):
        write_sequence(tmp_path / name, [], CAMERA, 25)
    assert list(tmp_path.iterdir()) == []
