"""Synthetic depth sequences: a posed body in a room, rendered, made noisy, written with ground truth.

Pipeline (:func:`synthesize`): world-frame poses -> camera placement and scene
(:mod:`depthtrack.synth.scene`) -> GL depth render of body + floor + back wall
(:class:`depthtrack.render.FrameRenderer`) -> ToF noise (:mod:`depthtrack.synth.noise`)
-> ``write_sequence`` with the 15 contract joints and the Plug-in Gait markers
(:mod:`depthtrack.body.markers`) as ground truth, and every setting under
``sequence.json["synth"]``.

Sources: a BVH file (:func:`synthesize_bvh`, retargeted onto the default body and
resampled with slerp) or a built-in motion (:func:`synthesize_procedural`).
"""
from __future__ import annotations

import os

import numpy as np

from ..camera import Camera
from ..contract import JOINT_NAMES
from ..errors import InputError
from ..progress import Progress
from ..body.markers import MARKER_NAMES, marker_vertices
from .noise import noise_from_name
from .scene import place_camera, scene_meshes, transform_poses

#: Pose-to-ground-truth batch size (bounds memory on long sequences).
_CHUNK = 256


def ground_truth(body, poses, vertices):
    """Contract joints (F, 15, 3) and marker positions (F, M, 3) for camera-frame poses (F, D)."""
    poses = np.asarray(poses, float)
    joints = np.empty((len(poses), len(JOINT_NAMES), 3))
    markers = np.empty((len(poses), len(vertices), 3))
    for s in range(0, len(poses), _CHUNK):
        chunk = poses[s:s + _CHUNK]
        joints[s:s + _CHUNK] = body.joint_positions(chunk)
        markers[s:s + _CHUNK] = np.asarray(body.posed_vertices(chunk))[:, vertices]
    return joints, markers


def synthesize(out, body, world_poses, fps: float, camera="sr4000", distance=None, azimuth=0.0,
               camera_height=None, noise="tof", seed=0, depth_scale=0.001, source=None,
               quiet=True, renderer=None, subject=None, pitch=None) -> dict:
    """Render, add noise and write a synthetic sequence.

    Parameters
    ----------
    out : path-like
        Sequence directory (or ``.npz``) to write, atomically.
    body : BodyModel
    world_poses : (F, D) float
        Poses in a world frame with the model's axes (y down), floor horizontal.
    fps : float
    camera : str or Camera
        A preset name from :data:`depthtrack.camera.CAMERA_PRESETS` or intrinsics.
    distance, azimuth, camera_height : see :func:`depthtrack.synth.scene.place_camera`.
    pitch : float or None
        Downward tilt of the camera in degrees (``place_camera``'s ``pitch_deg``).
    noise : {"tof", "none"} or ToFNoise
    seed : int
        Seeds the noise generator.
    depth_scale : float
    source : dict or None
        What the poses came from, stored in ``synth.source``.
    renderer : FrameRenderer or None
        Reused when given (must match the camera).
    subject : dict or None
        The subject's build (:func:`depthtrack.synth.subject.make_subject`'s description),
        written as ``synth.shape``: ground truth for evaluation, never read by the tracker.

    Returns
    -------
    dict
        The ``synth`` block written to sequence.json.
    """
    camera_name = camera if isinstance(camera, str) else "custom"
    cam = Camera.preset(camera) if isinstance(camera, str) else camera
    world_poses = np.asarray(world_poses, float)
    if len(world_poses) == 0:
        raise InputError(None, "no frames to synthesize")
    if isinstance(noise, str):
        try:
            noise_model = noise_from_name(noise, camera_name, depth_scale)
        except ValueError as exc:
            raise InputError(None, str(exc)) from None
    else:
        noise_model = noise
    placement = place_camera(cam, body, world_poses, distance=distance, azimuth_deg=azimuth,
                             height=camera_height, pitch_deg=pitch,
                             max_depth=noise_model.max_range if noise_model is not None else np.inf)
    poses = transform_poses(world_poses, placement.world_to_camera)
    meshes = scene_meshes(placement)
    vertices = marker_vertices(body)
    joints, markers = ground_truth(body, poses, vertices)

    owned = None
    if renderer is None:
        from ..render import FrameRenderer

        renderer = owned = FrameRenderer(cam)
    rng = np.random.default_rng(seed)

    def frames():
        with Progress(len(poses), "frames", quiet=quiet) as progress:
            for pose in poses:
                depth = renderer.render(body, pose, extra_meshes=meshes)
                if noise_model is not None:
                    depth = noise_model.apply(depth, rng)
                else:
                    depth = np.where(depth > 65535 * depth_scale, 0.0, depth)
                yield depth
                progress.update()

    synth = {
        "generator": "depthtrack synth",
        "source": dict(source or {}),
        "camera_preset": camera_name,
        "placement": placement.to_dict(),
        "scene": {"floor": True, "back_wall": True, "floor_y_world": round(placement.floor_y, 4)},
        "noise": noise_model.to_dict() if noise_model is not None else {"model": "none"},
        "seed": int(seed),
        "body": {"height_m": round(float(body.height), 4), "mesh": getattr(body, "mesh_name", "full"),
                 "vertices": int(len(body.mesh.vertices))},
        "markers": {"placement": "Plug-in Gait names, one mesh vertex each",
                    "vertices": [int(v) for v in vertices]},
    }
    if subject is not None:
        synth["shape"] = dict(subject)
    from ..io.sequence import write_sequence

    try:
        write_sequence(out, frames(), cam, fps, depth_scale=depth_scale, joints=joints,
                       markers=markers, marker_names=MARKER_NAMES,
                       subject={"height_m": round(float(body.height), 4)}, extra={"synth": synth})
    finally:
        if owned is not None:               # a renderer the caller gave stays the caller's
            owned.release()
    return synth


def _window(poses, fps, start, seconds, path=None):
    n = len(poses)
    first = int(round(start * fps))
    if not 0 <= first < n:
        raise InputError(path, f"--start {start} s is outside the motion (0 to {(n - 1) / fps:.2f} s)")
    last = n if seconds is None else min(n, first + max(1, int(round(seconds * fps))))
    return poses[first:last]


def synthesize_bvh(motion_path, out, fps=25.0, start=0.0, seconds=None, camera="sr4000",
                   distance=None, azimuth=0.0, height=1.75, noise="tof", seed=0, units=None,
                   camera_height=None, quiet=True, body=None, skip_leading_jump=True,
                   subject=None, joint_map=None, pitch=None) -> dict:
    """Synthesize a sequence from a BVH file (see :func:`synthesize`).

    The motion is retargeted onto the default body of the given height (full mesh),
    resampled to ``fps`` by slerp, cut to ``[start, start + seconds)``. With
    ``skip_leading_jump``, frames the motion teleports out of at its start
    (:meth:`BvhMotion.leading_jump`, e.g. CMU's calibration T-pose) are dropped first and
    ``start`` counts from the frame after them; ``sequence.json`` records how many.
    ``joint_map`` (``{our joint: file joint}`` or a JSON file) names joints the BVH
    reader's naming conventions do not find.
    """
    from ..body import BodyModel

    body = BodyModel.default(height=height, mesh="full") if body is None else body
    poses, source = bvh_world_poses(motion_path, body, fps, start, seconds, units,
                                    skip_leading_jump, joint_map)
    return synthesize(out, body, poses, fps, camera=camera, distance=distance, azimuth=azimuth,
                      camera_height=camera_height, noise=noise, seed=seed, source=source, quiet=quiet,
                      subject=subject, pitch=pitch)


def bvh_world_poses(motion_path, body, fps=25.0, start=0.0, seconds=None, units=None,
                    skip_leading_jump=True, joint_map=None):
    """A BVH motion as :func:`synthesize_bvh` renders it: ``(poses (F, D), source dict)``,
    the world-frame poses of ``body`` (retargeted, leading jump skipped, resampled to
    ``fps``, cut to ``[start, start + seconds)``) and the ``synth.source`` block."""
    from ..io.bvh import read_bvh
    from ..motion.retarget import canonical_axes, resample_poses, retarget, subject_height

    motion = read_bvh(motion_path, units=units, joint_map=joint_map)
    motion.contract_joint_indices()     # refuse a skeleton we cannot map before any work
    to_world = np.eye(4)
    to_world[:3, :3] = canonical_axes(motion)     # BVH world -> y-down world facing like the rest pose
    scale = float(body.height) / subject_height(motion, body)
    poses = retarget(motion, body, world_to_camera=to_world, scale=scale)
    skipped = motion.leading_jump() if skip_leading_jump else 0
    poses = poses[skipped:]
    duration = (len(poses) - 1) * motion.frame_time
    if not 0.0 <= start <= duration:
        raise InputError(motion_path, f"--start {start} s is outside the motion (0 to {duration:.2f} s)")
    poses = resample_poses(poses, motion.fps, fps, start=start, duration=seconds)
    source = {"kind": "bvh", "file": os.path.basename(os.fspath(motion_path)),
              "units_m": motion.units_m, "units_source": motion.units_source,
              "frames": motion.n_frames, "fps": round(motion.fps, 6),
              "joint_names": motion.convention(), "joint_map": motion.joint_map,
              "skipped_leading_frames": skipped,
              "skipped_because": ("the motion jumps out of them faster than a body moves "
                                  "(a calibration pose)") if skipped else None,
              "start_s": start,
              "seconds": None if seconds is None else float(seconds),
              "retarget": {"method": "bone directions, twist from BVH, hip centre follows BVH",
                           "root_scale": round(scale, 6)}}
    return poses, source


def synthesize_procedural(name, out, fps=25.0, start=0.0, seconds=None, camera="sr4000",
                          distance=None, azimuth=0.0, height=1.75, noise="tof", seed=0,
                          camera_height=None, quiet=True, body=None, subject=None, pitch=None) -> dict:
    """Synthesize a sequence from a built-in motion (see :mod:`depthtrack.synth.procedural`)."""
    from ..body import BodyModel

    body = BodyModel.default(height=height, mesh="full") if body is None else body
    poses = procedural_world_poses(name, body, fps, start, seconds)
    source = {"kind": "procedural", "name": name, "start_s": start,
              "seconds": None if seconds is None else float(seconds)}
    return synthesize(out, body, poses, fps, camera=camera, distance=distance, azimuth=azimuth,
                      camera_height=camera_height, noise=noise, seed=seed, source=source, quiet=quiet,
                      subject=subject, pitch=pitch)


def procedural_world_poses(name, body, fps=25.0, start=0.0, seconds=None):
    """A built-in motion as :func:`synthesize_procedural` renders it: world-frame poses
    ``(F, D)`` of ``body``, cut to ``[start, start + seconds)``."""
    from .procedural import PROCEDURAL_MOTIONS, procedural_motion

    if name not in PROCEDURAL_MOTIONS:
        raise InputError(None, f"unknown procedural motion {name!r}; known: {', '.join(PROCEDURAL_MOTIONS)}")
    total = None if seconds is None else start + seconds
    return _window(procedural_motion(name, body, fps, total), fps, start, seconds)


def rendered_poses(meta, motion_dir=None):
    """The body and the camera-frame poses a synthetic sequence was rendered with, rebuilt
    from its ``sequence.json`` (``meta``: the parsed file): ``(body, poses (F, D))``.

    The subject is rebuilt from ``synth.shape`` (scales, height, clothing and its seed)
    when there, else the default body of ``synth.body.height_m``; the motion from
    ``synth.source`` (a BVH file is looked for by name in ``motion_dir``); the camera
    frame from ``synth.placement``. For oracle figures (the true body at the true poses);
    the tracker never reads it.

    Raises
    ------
    InputError
        Not a synthetic sequence, or its motion file is not in ``motion_dir``.
    """
    from ..body import BodyModel
    from ..body.shape import BodyShape
    from .subject import make_subject

    synth = meta.get("synth") if isinstance(meta, dict) else None
    if not isinstance(synth, dict) or "source" not in synth or "placement" not in synth:
        raise InputError(None, "not a synthetic sequence (sequence.json has no synth block)")
    fps = float(meta["fps"])
    shape = synth.get("shape")
    if isinstance(shape, dict) and "scales" in shape:
        body, _ = make_subject(shape.get("height_m"), BodyShape.from_dict(shape["scales"]),
                               shape.get("seed"), (shape.get("clothing") or {}).get("kind", "none"))
    else:
        body = BodyModel.default(height=float(synth["body"]["height_m"]), mesh="full")
    src = synth["source"]
    if src.get("kind") == "procedural":
        world = procedural_world_poses(src["name"], body, fps, src["start_s"], src.get("seconds"))
    elif src.get("kind") == "bvh":
        path = os.path.join(os.fspath(motion_dir or "."), src["file"])
        if not os.path.isfile(path):
            raise InputError(path, "the sequence's motion file is not there (give its folder)")
        world, _ = bvh_world_poses(path, body, fps, src["start_s"], src.get("seconds"),
                                   units=src.get("units_m"),
                                   skip_leading_jump=bool(src.get("skipped_leading_frames")),
                                   joint_map=src.get("joint_map"))
    else:
        raise InputError(None, f"cannot rebuild a synthetic source of kind {src.get('kind')!r}")
    return body, transform_poses(world, np.asarray(synth["placement"]["world_to_camera"], float))
