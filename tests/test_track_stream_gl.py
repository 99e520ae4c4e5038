"""track_stream yields frame by frame; tracking and the height fit leave no GL object behind."""
import gc
from types import SimpleNamespace

import numpy as np
import pytest

from depthtrack.body import BodyModel
from depthtrack.camera import Camera

CAMERA = Camera.preset("sr4000")


def _segment(depth, camera):
    mask = depth > 0
    return SimpleNamespace(mask=mask, points=camera.backproject(depth)[mask], floor_plane=None)


@pytest.fixture(scope="module")
def frames():
    from depthtrack.render import FrameRenderer

    body = BodyModel.default(1.75)
    poses = np.zeros((4, 48))
    poses[:, 2] = 3.2
    poses[:, 14] = np.linspace(-0.4, -0.8, 4)            # left arm rising
    with FrameRenderer(CAMERA) as renderer:
        return body, poses, [renderer.render(body, p).astype(np.float32) for p in poses]


def _live_gl_objects():
    """GL objects still alive (created and not released), found through the garbage collector."""
    import moderngl

    gc.collect()
    kinds = (moderngl.Buffer, moderngl.Texture, moderngl.Framebuffer, moderngl.Renderbuffer,
             moderngl.VertexArray)
    return sum(1 for o in gc.get_objects()
               if isinstance(o, kinds) and type(o.mglo).__name__ != "InvalidObject")


def _drain(ctx) -> int:
    """Release what was collected unreleased; returns how many."""
    leaked = [o for o in ctx.objects if type(o).__name__ != "InvalidObject"]
    for o in leaked:
        o.release()
    ctx.objects.clear()
    return len(leaked)


def test_track_stream_yields_each_frame_before_reading_the_next(frames):
    from depthtrack import track_stream
    from depthtrack.track import TrackerSettings

    body, truth, depths = frames
    pulled = []

    def source():
        for d in depths:
            pulled.append(1)
            yield d

    seen = []
    for f in track_stream(source(), CAMERA, body=body, method="hc", segmenter=_segment,
                          settings=TrackerSettings(heading={"frames": 0, "retro_frames": 0},
                                                   start={"complete_fraction": 0.0})):
        seen.append((f.index, len(pulled)))
        err = np.linalg.norm(f.joints - body.joint_positions(truth[f.index]), axis=-1)
        assert err.mean() < 0.05
    assert seen == [(0, 1), (1, 2), (2, 3), (3, 4)]


def test_tracking_and_the_height_fit_release_every_gl_object(frames):
    from depthtrack.render import gl_context
    from depthtrack.track import (HeadingSettings, HeightSettings, TrackerSettings, fit_body_height,
                                  track_stream)

    body, _, depths = frames
    ctx = gl_context()
    mode = ctx.gc_mode
    # collected GL objects land in ctx.objects (released ones as InvalidObject)
    ctx.gc_mode = "context_gc"
    _drain(ctx)
    try:
        from depthtrack.render import TileRenderer

        TileRenderer(body, CAMERA, tile=16)             # dropped unreleased: the check sees it
        gc.collect()
        assert _drain(ctx) > 0
        start = _live_gl_objects()
        out = list(track_stream(iter(depths), CAMERA, body=body, method="hc+ep",
                                segmenter=_segment, detector=lambda d, c, f: [],
                                settings=TrackerSettings(heading=HeadingSettings(
                                    frames=2, every=1, recheck_tile=32, judge_tile=256))))
        assert [f.index for f in out] == [0, 1, 2, 3] and all(f.pose is not None for f in out)
        assert _live_gl_objects() == start
        fitted, info = fit_body_height(depths[0], _segment(depths[0], CAMERA), CAMERA,
                                       segmenter=_segment,
                                       settings=TrackerSettings(height=HeightSettings(steps=1, walk=1)))
        assert len(info["candidates"]) >= 3
        assert _live_gl_objects() == start
        gc.collect()
        assert _drain(ctx) == 0, "GL objects were dropped without release()"
    finally:
        _drain(ctx)
        ctx.gc_mode = mode


def test_the_rechecks_renderer_scores_the_uploaded_frame_and_belongs_to_the_set(frames):
    from depthtrack.render import TileRenderer
    from depthtrack.track.renderers import RendererSet

    body, truth, depths = frames
    render_body = body.with_mesh("decimated")
    roi = (30.0, 0.0, 140.0)
    start = _live_gl_objects()
    with RendererSet(render_body, CAMERA, tile=64) as renderers, \
            TileRenderer(render_body, CAMERA, tile=32) as fresh:
        assert renderers.at_tile(0) is renderers.coarse and renderers.at_tile(64) is renderers.coarse
        renderers.upload(SimpleNamespace(observed=depths[1], roi=roi))
        late = renderers.at_tile(32)              # made after the upload: it scores that frame
        assert late is renderers.at_tile(32) and late.tile == 32
        for k in (1, 3):
            if k == 3:                            # and every frame uploaded after it
                renderers.upload(SimpleNamespace(observed=depths[3], roi=roi))
            fresh.set_observation(depths[k], roi=roi)
            costs = late.costs(truth)
            np.testing.assert_allclose(costs, fresh.costs(truth), rtol=1e-6)
            assert np.argmin(costs) == k          # the frame's own pose explains it best
    assert _live_gl_objects() == start


def test_renderers_release_on_leaving_with():
    from depthtrack.render import FrameRenderer, TileRenderer

    body = BodyModel.default(1.75, mesh="decimated")
    start = _live_gl_objects()
    with TileRenderer(body, CAMERA, tile=32) as tiles, FrameRenderer(CAMERA) as frame:
        frame.render(body, body.default_pose(position=(0, 0, 2.5)))
        assert _live_gl_objects() > start
        tiles.set_body(BodyModel.default(1.6, mesh="decimated"))    # same mesh, other height
        with pytest.raises(ValueError):
            tiles.set_body(BodyModel.default(1.6))                  # another mesh
    assert _live_gl_objects() == start
    tiles.release()                 # idempotent


def test_the_front_back_check_makes_do_with_the_frames_there_are(frames):
    """A clip shorter than HeadingSettings.frames after the start is checked on the frames
    it has, when they are at least min_frames; with fewer the check is skipped."""
    from depthtrack.track import TrackerSettings
    from depthtrack.track.tracker import Tracker

    body, _, depths = frames
    for min_frames, checked in ((2, 3), (10, None)):
        settings = TrackerSettings(heading={"frames": 25, "min_frames": min_frames},
                                   start={"complete_fraction": 0.0})
        with Tracker(body, CAMERA, method="hc", segmenter=_segment, settings=settings) as t:
            out = list(t.stream(depths))
            check = t.state.init_info.get("heading_check")
        assert [i for i, x in out if x is not None] == [0, 1, 2, 3]
        assert (check and check["frames"]) == checked
