"""ROS 1 and ROS 2 bags: written with rosbags' writers from a synthetic sequence, read back."""
import json

import numpy as np
import pytest

from depthtrack import Camera, InputError
from depthtrack.cli import main
from depthtrack.io.registry import open_sequence

from rosbag_writers import write_ros1_bag, write_ros2_bag

CAMERA = Camera(width=32, height=24, fx=30.0, fy=31.0, cx=15.5, cy=11.5)


@pytest.fixture(scope="module")
def synthetic(tmp_path_factory):
    """A 2-frame synthetic ToF sequence (SR4000 size) as our PNG directory."""
    from depthtrack.synth.generate import synthesize_procedural

    path = tmp_path_factory.mktemp("synth") / "wave"
    synthesize_procedural("wave", path, seconds=0.08, quiet=True)
    return open_sequence(path)


def _same_tracker_input(a, b):
    """What the tracker reads: frames (float32 metres), camera, frame rate."""
    assert len(a) == len(b) and a.camera == b.camera and a.fps == pytest.approx(b.fps)
    for i in range(len(a)):
        da, db = a.depth(i), b.depth(i)
        assert da.dtype == db.dtype == np.float32 and np.array_equal(da, db), f"frame {i}"


def test_ros1_16uc1_and_ros2_mcap_32fc1_read_back(synthetic, tmp_path):
    n = len(synthetic)
    raw = [synthetic.raw_depth(i) for i in range(n)]
    metres = [synthetic.depth(i) for i in range(n)]
    bag1 = write_ros1_bag(tmp_path / "seq.bag", raw, synthetic.camera, encoding="16UC1")
    bag2 = write_ros2_bag(tmp_path / "seq_mcap", metres, synthetic.camera, encoding="32FC1")
    for path, reader, encoding in ((bag1, "ros1-bag", "16UC1"), (bag2, "ros2-bag", "32FC1")):
        seq = open_sequence(path)
        assert seq.reader == reader and seq.meta["source"]["encoding"] == encoding
        assert seq.meta["source"]["camera_info"] == "/camera/depth/camera_info"
        assert np.allclose(seq.timestamps, np.arange(n) / 25.0) and seq.fps == pytest.approx(25.0)
        # Frames within 1 mm (here bit-identical: the bag holds the same values), same camera:
        # the tracker reads exactly what it reads from the PNG directory.
        for i in range(n):
            assert np.abs(seq.depth(i) - metres[i]).max() <= 0.001
        _same_tracker_input(seq, synthetic)
        # convert: back to a PNG directory with the same raw frames.
        out = tmp_path / f"back_{reader}"
        assert main(["convert", str(path), str(out), "--quiet"]) == 0
        back = open_sequence(out)
        assert back.camera == synthetic.camera and back.depth_scale == 0.001
        assert all(np.array_equal(back.raw_depth(i), raw[i]) for i in range(n))
        meta = json.loads((out / "sequence.json").read_text())
        assert meta["source"]["topic"] and len(meta["source"]["timestamps"]) == n


def test_ros2_sqlite_bag_and_its_db3_file(tmp_path):
    rng = np.random.default_rng(1)
    depth = rng.uniform(0.5, 3.0, (3, 24, 32)).astype(np.float32)
    depth[0, :, :4] = np.nan  # 32FC1: NaN = no reading
    bag = write_ros2_bag(tmp_path / "sq", depth, CAMERA, encoding="32FC1", storage="sqlite3")
    for path in (bag, next(bag.glob("*.db3"))):
        seq = open_sequence(path)
        assert seq.camera == CAMERA and len(seq) == 3
        d0 = seq.depth(0)
        assert np.all(d0[:, :4] == 0) and np.allclose(d0[:, 4:], depth[0, :, 4:])


def test_depth_topic_choice(tmp_path):
    raw = np.full((3, 24, 32), 1500, np.uint16)
    two = write_ros1_bag(tmp_path / "two.bag", raw, CAMERA, topic="/cam_a/depth/image_raw",
                         info_topic="/cam_a/depth/camera_info",
                         extra_image_topics=("/cam_b/depth/image_raw",))
    with pytest.raises(InputError) as info:
        open_sequence(two)
    text = str(info.value)
    assert "two.bag" in text and "--topic" in text and "\n" not in text
    assert "/cam_a/depth/image_raw" in text and "/cam_b/depth/image_raw" in text
    seq = open_sequence(two, topic="/cam_b/depth/image_raw")
    # cam_b has no camera info of its own; the nearest one (sharing no more than "/") is
    # still the only one, so it is used.
    assert seq.camera == CAMERA and seq.depth(2)[5, 5] == pytest.approx(1.5)
    with pytest.raises(InputError, match="no image topic '/nope'"):
        open_sequence(two, topic="/nope")
    # On the command line: one line, exit 2.
    assert main(["convert", str(two), str(tmp_path / "out"), "--quiet"]) == 2
    assert not (tmp_path / "out").exists()


def test_realsense_layout_and_depth_units(tmp_path):
    raw = np.full((2, 24, 32), 4000, np.uint16)
    topic = "/device_0/sensor_0/Depth_0/image/data"
    bag = write_ros1_bag(tmp_path / "rs.bag", raw, CAMERA, topic=topic,
                         info_topic="/device_0/sensor_0/Depth_0/info/camera_info",
                         extra_image_topics=("/device_0/sensor_1/Color_0/image/data",))
    seq = open_sequence(bag)
    assert seq.meta["source"]["topic"] == topic and seq.depth_scale == 0.001
    assert seq.depth(0)[0, 0] == pytest.approx(4.0)
    seq = open_sequence(bag, depth_units=0.0001)       # a D400 set to 100 um units
    assert seq.depth(1)[0, 0] == pytest.approx(0.4)
    out = tmp_path / "rs_seq"
    assert main(["convert", str(bag), str(out), "--depth-units", "0.0001", "--quiet"]) == 0
    assert json.loads((out / "sequence.json").read_text())["depth_scale"] == 0.0001
    assert open_sequence(out).depth(0)[0, 0] == pytest.approx(0.4)


@pytest.mark.slow
def test_bag_tracks_to_the_same_joints_as_the_png_directory(synthetic, tmp_path):
    """End to end through the tracker (2 frames, front/back check off: about 6 s)."""
    from depthtrack.track.tracker import TrackerSettings, run_tracking

    bag = write_ros2_bag(tmp_path / "seq_mcap", [synthetic.depth(i) for i in range(len(synthetic))],
                         synthetic.camera, encoding="32FC1")
    seq = open_sequence(bag)
    seq.subject_height = synthetic.subject_height  # a bag does not carry the subject's height
    settings = TrackerSettings(heading_frames=0)
    ref, _, _ = run_tracking(synthetic, method="hc", settings=settings)
    got, _, _ = run_tracking(seq, method="hc", settings=settings)
    assert np.isfinite(ref.joints).any()
    assert np.array_equal(np.isnan(ref.joints), np.isnan(got.joints))
    assert np.nanmax(np.abs(ref.joints - got.joints)) == 0.0


def test_compressed_depth_topics(tmp_path):
    from rosbag_writers import QUANT_A, QUANT_B

    rng = np.random.default_rng(2)
    raw = rng.integers(0, 6000, (3, 24, 32)).astype(np.uint16)
    bag = write_ros1_bag(tmp_path / "c16.bag", raw, CAMERA, topic="/camera/depth/image_raw/compressedDepth",
                         compressed=True)
    seq = open_sequence(bag)
    assert seq.meta["source"]["compressed"] and seq.camera == CAMERA
    assert all(np.array_equal(seq.raw_depth(i), raw[i]) for i in range(3))   # PNG: lossless
    # 32FC1 travels as quantised inverse depth: z = A / (v - B), v = 0 = no reading.
    metres = rng.uniform(0.5, 4.0, (2, 24, 32)).astype(np.float32)
    metres[:, 0] = np.nan
    bag = write_ros1_bag(tmp_path / "c32.bag", metres, CAMERA, encoding="32FC1",
                         topic="/camera/depth/image_raw/compressedDepth", compressed=True)
    seq = open_sequence(bag)
    v = np.rint(QUANT_A / metres[1, 1:] + QUANT_B)
    expected = QUANT_A / (v - QUANT_B)
    d = seq.depth(1)
    assert np.all(d[0] == 0) and np.allclose(d[1:], expected, rtol=1e-5)
    assert np.abs(d[1:] - metres[1, 1:]).max() < 4.0 ** 2 / QUANT_A / 2 + 1e-3   # the codec's own step
    # A raw depth topic beside its compressed twin: the raw one is chosen.
    both = write_ros1_bag(tmp_path / "both.bag", raw, CAMERA, topic="/camera/depth/image_raw/compressedDepth",
                          compressed=True, extra_image_topics=("/camera/depth/image_raw",))
    assert open_sequence(both).meta["source"]["topic"] == "/camera/depth/image_raw"
