"""Reader registry, array sequences, TUM folders and ``depthtrack convert``."""
import json
import shutil
import sys
import textwrap

import numpy as np
import pytest

from depthtrack import Camera, InputError
from depthtrack.cli import main
from depthtrack.io import registry
from depthtrack.io.arrays import sequence_from_arrays
from depthtrack.io.registry import (DepthSequence, Reader, choose_reader, open_sequence,
                                    parse_intrinsics, register_reader, unregister_reader)
from depthtrack.io.sequence import Sequence, _write_png16, write_sequence

from rosbag_writers import write_ros1_bag

CAMERA = Camera(width=32, height=24, fx=30.0, fy=31.0, cx=15.5, cy=11.5)


def _frames(n=4, seed=0):
    rng = np.random.default_rng(seed)
    depth = rng.uniform(0.5, 4.0, (n, 24, 32))
    depth[:, :2] = 0.0  # no reading
    return depth


# ------------------------------------------------------------------ registry
def test_registry_chooses_by_suffix_and_by_content(tmp_path):
    seq_dir = write_sequence(tmp_path / "seq", _frames(), CAMERA, 25)
    npz = write_sequence(tmp_path / "seq.npz", _frames(), CAMERA, 25)
    bag = write_ros1_bag(tmp_path / "rec.bag", np.rint(_frames() * 1000).astype(np.uint16), CAMERA)
    assert choose_reader(seq_dir).name == "depthtrack-directory"
    assert choose_reader(npz).name == "depthtrack-npz"
    assert choose_reader(bag).name == "ros1-bag"
    # Content alone: the same files under names that say nothing.
    shutil.copy(bag, tmp_path / "recording.dat")
    shutil.copy(npz, tmp_path / "frames.bin")
    assert choose_reader(tmp_path / "recording.dat").name == "ros1-bag"
    assert choose_reader(tmp_path / "frames.bin").name == "depthtrack-npz"
    seq = open_sequence(tmp_path / "recording.dat")
    assert len(seq) == 4 and seq.camera == CAMERA
    # A suffix that lies loses to the content: a bag named .mkv is read as a bag.
    shutil.copy(bag, tmp_path / "fake.mkv")
    assert choose_reader(tmp_path / "fake.mkv").name == "ros1-bag"
    (tmp_path / "notes.txt").write_text("hello")
    with pytest.raises(InputError, match="notes.txt: not a readable depth recording"):
        open_sequence(tmp_path / "notes.txt")
    with pytest.raises(InputError, match="no such file"):
        open_sequence(tmp_path / "absent.bag")


def test_native_sequence_implements_the_protocol(tmp_path):
    seq = open_sequence(write_sequence(tmp_path / "seq", _frames(), CAMERA, 20))
    assert isinstance(seq, Sequence) and isinstance(seq, DepthSequence)
    assert np.allclose(seq.timestamps, np.arange(4) / 20)
    assert seq.reader == "depthtrack-directory"
    arrays = sequence_from_arrays(_frames(), CAMERA, fps=20)
    assert isinstance(arrays, DepthSequence)


def test_register_reader_through_the_api(tmp_path):
    calls = []

    def open_fake(path, scale=1.0):
        calls.append(scale)
        depth = np.full((2, 24, 32), 1.5 * scale)
        return sequence_from_arrays(depth, CAMERA, fps=10)

    fake = Reader("fake-depth", open_fake, suffixes=(".fakedepth",),
                  sniff=lambda path, head: head.startswith(b"FAKEDEPTH"), options=("scale",))
    register_reader(fake)
    try:
        (tmp_path / "a.fakedepth").write_bytes(b"FAKEDEPTH v1")
        (tmp_path / "b.raw").write_bytes(b"FAKEDEPTH v1")
        (tmp_path / "c.fakedepth").write_bytes(b"something else")
        assert choose_reader(tmp_path / "a.fakedepth") is fake     # by suffix
        assert choose_reader(tmp_path / "b.raw") is fake           # by content
        with pytest.raises(InputError, match="not a readable depth recording"):
            choose_reader(tmp_path / "c.fakedepth")                # the suffix alone is not enough
        seq = open_sequence(tmp_path / "b.raw", scale=2.0)
        assert calls == [2.0] and seq.depth(1)[0, 0] == pytest.approx(3.0)
        assert seq.reader == "fake-depth"
        # Options the chosen reader does not take are refused by name.
        with pytest.raises(InputError, match="option topic does not apply to fake-depth"):
            open_sequence(tmp_path / "b.raw", topic="/depth")
        # Common options apply to every reader.
        seq = open_sequence(tmp_path / "b.raw", intrinsics="40,41,16,12", depth_units=0.002, fps=5)
        assert (seq.camera.fx, seq.camera.fy, seq.camera.cx, seq.fps, seq.depth_scale) == (40, 41, 16, 5, 0.002)
    finally:
        unregister_reader("fake-depth")
    assert all(r.name != "fake-depth" for r in registry.readers())


def test_entry_point_group_loads_a_plugin(tmp_path, monkeypatch):
    # A distribution on sys.path declaring a reader under depthtrack.readers, as
    # another package's pyproject.toml would.
    dist = tmp_path / "depthplug-0.1.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: depthplug\nVersion: 0.1\n")
    (dist / "entry_points.txt").write_text("[depthtrack.readers]\nplug = depthplug:READERS\n")
    (tmp_path / "depthplug.py").write_text(textwrap.dedent("""
        import numpy as np
        from depthtrack import Camera
        from depthtrack.io.arrays import sequence_from_arrays
        from depthtrack.io.registry import Reader

        def _open(path):
            cam = Camera(width=8, height=6, fx=10, fy=10, cx=3.5, cy=2.5)
            return sequence_from_arrays(np.full((3, 6, 8), 2.0), cam, fps=15)

        READERS = {"plug": Reader("plug-depth", _open, suffixes=(".plug",))}
    """))
    monkeypatch.syspath_prepend(str(tmp_path))
    try:
        assert "plug-depth" in registry.load_plugins(force=True)
        (tmp_path / "x.plug").write_bytes(b"")
        seq = open_sequence(tmp_path / "x.plug")
        assert len(seq) == 3 and seq.fps == 15 and seq.depth(0)[0, 0] == 2.0
    finally:
        unregister_reader("plug-depth")
        sys.modules.pop("depthplug", None)


def test_parse_intrinsics():
    cam = parse_intrinsics("freiburg1", 640, 480)
    assert (cam.fx, cam.fy, cam.cx, cam.cy) == (517.3, 516.5, 318.6, 255.3)
    assert parse_intrinsics("sr4000", 176, 144) == Camera.preset("sr4000")
    assert parse_intrinsics("1,2,3,4", 8, 6).cy == 4.0
    with pytest.raises(InputError, match="preset 'sr4000' is 176 x 144"):
        parse_intrinsics("sr4000", 640, 480)
    with pytest.raises(InputError, match="neither fx,fy,cx,cy nor a preset"):
        parse_intrinsics("1,2,3", 8, 6)


# ------------------------------------------------------------------ arrays
def test_sequence_from_arrays_uint16_and_float():
    depth = _frames()
    raw = np.rint(depth * 5000).astype(np.uint16)
    seq = sequence_from_arrays(raw, CAMERA, fps=30, depth_scale=0.0002)
    assert np.array_equal(seq.raw_depth(2), raw[2])
    assert np.allclose(seq.depth(2), raw[2] * 0.0002, atol=1e-6)
    floats = depth.copy()
    floats[:, 2:4] = np.nan  # NaN = no reading
    seq = sequence_from_arrays(floats, CAMERA, fps=30)
    d = seq.depth(1)
    assert d.dtype == np.float32 and np.all(d[:4] == 0) and np.allclose(d[4:], depth[1, 4:], atol=1e-6)
    assert np.abs(seq.raw_depth(1)[4:] * 0.001 - depth[1, 4:]).max() <= 0.0005 + 1e-9
    with pytest.raises(ValueError, match="need depth_scale"):
        sequence_from_arrays(raw, CAMERA)
    with pytest.raises(ValueError, match="camera is 32 x 24"):
        sequence_from_arrays(raw[:, :, :-1], CAMERA, depth_scale=0.001)


# ------------------------------------------------------------------ TUM
def _write_tum(folder, raw, times):
    (folder / "depth").mkdir(parents=True)
    lines = ["# depth maps", "# file: 'rgbd_dataset_freiburg1_xyz.bag'", "# timestamp filename"]
    for t, frame in zip(times, raw):
        name = f"depth/{t:.6f}.png"
        _write_png16(folder / name, frame)
        lines.append(f"{t:.6f} {name}")
    (folder / "depth.txt").write_text("\n".join(lines) + "\n")


def test_tum_folder_round_trip(tmp_path):
    raw = np.rint(_frames() * 5000).astype(np.uint16)
    times = 1305031102.160407 + np.array([0.0, 0.0333, 0.0667, 0.1003])
    folder = tmp_path / "rgbd_dataset_freiburg1_xyz"
    _write_tum(folder, raw, times)
    # Named like the benchmark's folders: freiburg1's published intrinsics.
    seq = open_sequence(folder)
    assert seq.reader == "tum-rgbd" and seq.camera.fx == 517.3 and seq.camera.shape == (24, 32)
    assert seq.depth_scale == pytest.approx(1 / 5000)
    assert np.allclose(seq.timestamps, times - times[0], atol=1e-6)
    assert seq.fps == pytest.approx(1 / 0.0334, rel=0.01)
    assert np.allclose(seq.depth(3), raw[3] / 5000.0, atol=1e-6)
    # Converted, read back: the same raw values (lossless), units, camera, times.
    out = tmp_path / "converted"
    assert main(["convert", str(folder), str(out), "--intrinsics", "30,31,15.5,11.5", "--quiet"]) == 0
    back = open_sequence(out)
    assert back.camera == CAMERA and back.depth_scale == pytest.approx(1 / 5000)
    assert all(np.array_equal(back.raw_depth(i), raw[i]) for i in range(4))
    assert np.allclose(back.timestamps, times - times[0], atol=1e-6)
    meta = json.loads((out / "sequence.json").read_text())
    assert meta["source"]["reader"] == "tum-rgbd" and meta["source"]["options"]["intrinsics"] == "30,31,15.5,11.5"
    # Without intrinsics and without a telling folder name: a one-line error asking for them.
    plain = tmp_path / "my_recording"
    shutil.copytree(folder, plain)
    with pytest.raises(InputError, match="my_recording: a TUM RGB-D folder has no intrinsics: give --intrinsics"):
        open_sequence(plain)


# ------------------------------------------------------------------ convert CLI
def test_convert_refuses_bad_input_and_foreign_output(tmp_path, capsys):
    (tmp_path / "notes.txt").write_text("hello")
    assert main(["convert", str(tmp_path / "notes.txt"), str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip()
    assert "notes.txt: not a readable depth recording" in err and "\n" not in err
    assert not (tmp_path / "out").exists()
    seq = write_sequence(tmp_path / "seq", _frames(), CAMERA, 25)
    foreign = tmp_path / "photos"
    foreign.mkdir()
    (foreign / "keep.jpg").write_bytes(b"x")
    assert main(["convert", str(seq), str(foreign)]) == 2
    assert "not an earlier output" in capsys.readouterr().err and (foreign / "keep.jpg").exists()
    assert main(["convert", str(seq), str(seq)]) == 2
    assert "is the input" in capsys.readouterr().err
    # A directory converts to the single-file form and back, unchanged.
    assert main(["convert", str(seq), str(tmp_path / "seq.npz"), "--quiet"]) == 0
    back = open_sequence(tmp_path / "seq.npz")
    orig = open_sequence(seq)
    assert all(np.array_equal(back.raw_depth(i), orig.raw_depth(i)) for i in range(4))


def test_convert_help_has_examples(capsys):
    assert main(["convert", "--help"]) == 0
    out = capsys.readouterr().out
    assert "examples:" in out and "--topic" in out and "--intrinsics" in out
