"""Overlay frames: skeleton pixels at the projected joints, silhouette = the rendered mask."""
import numpy as np
import pytest

from depthtrack.body import BodyModel
from depthtrack.camera import Camera
from depthtrack.contract import JOINT_NAMES
from depthtrack.errors import InputError
from depthtrack.evaluate import overlay
from depthtrack.io.sequence import open_sequence, write_sequence
from depthtrack.render import FrameRenderer

FRAMES = 4


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    root = tmp_path_factory.mktemp("overlay")
    body = BodyModel.default(height=1.7)
    camera = Camera.preset("sr4000")
    rng = np.random.default_rng(7)
    poses = np.tile(body.default_pose((0.1, -0.1, 3.2)), (FRAMES, 1))
    poses[:, 3:] += rng.normal(0.0, 0.1, (FRAMES, 45))
    renderer = FrameRenderer(camera)
    depth = np.stack([renderer.render(body, p) for p in poses])
    renderer.release()
    depth[depth == 0] = 4.5                                   # a wall behind the subject
    seq = open_sequence(write_sequence(root / "seq", depth, camera, 25.0))
    fitted = poses.copy()
    fitted[:, 0] += 0.06                                      # the "track" is 6 cm off
    fitted[2] = np.nan                                        # and has no pose in frame 2
    return {"root": root, "body": body, "camera": camera, "seq": seq, "fitted": fitted}


def test_skeleton_and_silhouette_pixels(scene):
    body, camera, seq, fitted = scene["body"], scene["camera"], scene["seq"], scene["fitted"]
    scale = overlay.upscale_factor(camera.width)
    assert scale == 3                                         # 176 px -> 528 px
    frames = list(overlay.overlay_frames(seq, fitted, body, label=False))
    assert len(frames) == FRAMES
    near, far = overlay.depth_range(seq)
    renderer = FrameRenderer(camera)
    for i, img in enumerate(frames):
        assert img.shape == (camera.height * scale, camera.width * scale, 3) and img.dtype == np.uint8
        base = np.repeat(np.repeat(overlay.colour_depth(seq.depth(i), near, far), scale, 0), scale, 1)
        if i == 2:                                            # no pose: the depth alone
            np.testing.assert_array_equal(img, base)
            continue
        uv = camera.project(body.joint_positions(fitted[i]))
        centres = np.rint(overlay.to_output_pixels(uv, scale)).astype(int)
        for k, (x, y) in enumerate(centres):
            assert tuple(img[y, x]) == overlay.JOINT_RGB, JOINT_NAMES[k]
        mask = renderer.render(body, fitted[i]) > 0
        big = np.repeat(np.repeat(mask, scale, 0), scale, 1)
        skeleton = np.zeros(big.shape, bool)                  # pixels the skeleton may cover
        for x, y in centres:
            skeleton[max(0, y - 12):y + 13, max(0, x - 12):x + 13] = True
        changed = np.any(img != base, axis=-1)
        # the silhouette changes exactly the rendered mask (bones aside, which stay near joints
        # or inside the body)
        assert not np.any(changed & ~big & ~skeleton)
        assert np.all(changed[big & ~skeleton])
        # without the skeleton: exactly the mask, filled translucently, its inner rim solid
        silhouette = overlay.overlay_frame(overlay.colour_depth(seq.depth(i), near, far), mask, None, scale)
        np.testing.assert_array_equal(np.any(silhouette != base, axis=-1), big)
        fill = np.rint((1 - overlay.SILHOUETTE_ALPHA) * base + overlay.SILHOUETTE_ALPHA *
                       np.array(overlay.SILHOUETTE_RGB)).astype(np.uint8)
        padded = np.pad(big, 1)
        rim = big & ~(padded[:-2, 1:-1] & padded[2:, 1:-1] & padded[1:-1, :-2] & padded[1:-1, 2:]
                      & padded[:-2, :-2] & padded[:-2, 2:] & padded[2:, :-2] & padded[2:, 2:])
        np.testing.assert_array_equal(silhouette[rim], np.broadcast_to(overlay.SILHOUETTE_RGB, (rim.sum(), 3)))
        np.testing.assert_array_equal(silhouette[big & ~rim], fill[big & ~rim])
        assert 0 < rim.sum() < 0.5 * big.sum()
    renderer.release()


def test_write_overlay_mp4_and_gif(scene):
    import cv2
    from PIL import Image

    seq, body, fitted = scene["seq"], scene["body"], scene["fitted"]
    mp4 = overlay.write_overlay(scene["root"] / "out.mp4", seq, fitted, body)
    assert mp4.suffix == ".mp4"                               # this OpenCV encodes mp4v
    cap = cv2.VideoCapture(str(mp4))
    assert cap.get(cv2.CAP_PROP_FPS) == pytest.approx(25.0)
    count, shape = 0, None
    while True:
        ok, frame = cap.read()
        if not ok:
            break
        count, shape = count + 1, frame.shape
    assert count == FRAMES and shape == (432, 528, 3)
    gif = overlay.write_overlay(scene["root"] / "out.gif", seq, fitted, body, fps=10)
    with Image.open(gif) as im:
        assert im.n_frames == FRAMES and im.size == (528, 432)
        assert im.info["duration"] == 100
    with pytest.raises(InputError):
        overlay.write_overlay(scene["root"] / "out.avi", seq, fitted, body)
    with pytest.raises(InputError):
        overlay.write_overlay(scene["root"] / "bad.mp4", seq, fitted[:2], body)
    assert not (scene["root"] / "bad.mp4").exists()


def test_mp4_falls_back_to_gif_without_an_encoder(scene, monkeypatch):
    import cv2
    from PIL import Image

    class NoEncoder:
        def __init__(self, *args):
            pass

        def isOpened(self):
            return False

        def release(self):
            pass

    monkeypatch.setattr(cv2, "VideoWriter", NoEncoder)
    written = overlay.write_overlay(scene["root"] / "fallback.mp4", scene["seq"], scene["fitted"], scene["body"])
    assert written == scene["root"] / "fallback.gif"
    assert not (scene["root"] / "fallback.mp4").exists()
    with Image.open(written) as im:
        assert im.n_frames == FRAMES
