"""glTF 2.0 export (``.glb`` / ``.gltf``): the fitted skinned body and its animation.

What the file holds:

* the shipped body mesh at the tracked body's size (the scaled zero pose, baked), skinned
  to 15 joint nodes named as our skeleton (``pelvis`` ... ``r_ankle``) plus a static
  ``head_centre`` node under ``neck``; the node tree is our kinematic tree;
* the bind (rest) pose is our zero pose (a relaxed A-pose, pelvis at the origin); the
  inverse bind matrices are the inverses of the joints' rest transforms (pure
  translations, as our rest frames are axis-aligned), so skinning the rest pose gives
  the mesh back;
* one animation, ``track``: one keyframe per frame at ``frame / fps`` seconds, LINEAR;
  a rotation channel (unit quaternions) for every joint node and a translation channel
  for ``pelvis`` (the root).

Axes and units: glTF is y up, metres, right-handed. Our poses live in the OpenCV camera
frame (x right, y down, z forward); the file's world is that frame turned 180 degrees
about x (``Y_UP_FROM_CAMERA``: x right, y up, z toward the viewer), origin at the depth
camera, so a glTF camera at the origin with no rotation looks where the depth camera
looked. The floor is wherever the camera saw it (not moved to y = 0; a tilted camera
gives a tilted floor).

The body's per-bone stretch, when it has one (``BodyModel.segment_scale``; the tracker
scales uniformly), is baked into the rest surface; glTF skinning then moves the few
centimetres around a stretched bone's parent joint slightly differently from ours.

Frames without a pose (NaN rows) hold the last known pose (leading ones the first), as
in ``track.bvh``: a keyframed animation has no "unknown".
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..body.gltf import gltf_bytes
from ..body.mesh import SkinnedMesh
from ..body.rotations import matrix_to_quat, rotvec_to_matrix
from ..contract import JOINT_INDEX
from ..io.atomic import write_bytes_atomic, write_text_atomic
from .axes import Y_UP_FROM_CAMERA
from ..io.track_output import hold_last_pose

#: Name of the animation in the file.
ANIMATION_NAME = "track"


def rest_skeleton(body):
    """The tracked body's rest (zero) pose in the model frame.

    Returns
    -------
    joints : (J, 3) float
        Skeleton joint positions, pelvis at the origin.
    head : (3,) float
        The contract head centre.
    vertices : (V, 3) float
        The scaled mesh surface.
    """
    zero = np.zeros(body.dof)
    joints = np.asarray(body.world_transforms(zero))[:, :3, 3]
    head = np.asarray(body.joint_positions(zero))[JOINT_INDEX["head"]]
    return joints, head, np.asarray(body.rest_vertices, float)


def animation_channels(body, poses):
    """Per-frame node rotations and root translation in glTF axes.

    Parameters
    ----------
    body : BodyModel
    poses : (F, D) float, finite

    Returns
    -------
    rotations : (F, J, 4) float32
        Each joint node's local rotation ``C R_j C`` as a unit quaternion (x, y, z, w),
        signs continuous over time.
    translation : (F, 3) float32
        The root node's translation ``C t``.
    """
    C = Y_UP_FROM_CAMERA
    poses = np.asarray(poses, float)
    F, J = len(poses), len(body.joint_names)
    local = rotvec_to_matrix(poses[:, 3:].reshape(F, J, 3))
    quats = matrix_to_quat(C @ local @ C)
    for i in range(1, F):   # q and -q are one rotation; keep neighbours on one hemisphere
        flip = np.sum(quats[i] * quats[i - 1], axis=-1) < 0
        quats[i, flip] *= -1.0
    return quats.astype(np.float32), (poses[:, :3] @ C.T).astype(np.float32)


def gltf_animated(body, poses, fps: float):
    """A ``pygltflib.GLTF2`` of the skinned body with the animation of ``poses (F, D)``.

    NaN rows hold the last pose (see the module docstring). Raises ValueError when no
    frame has a pose.
    """
    import pygltflib as g

    poses = hold_last_pose(poses)
    if poses is None:
        raise ValueError("the track has no frame with a pose; nothing to animate")
    joints, head, vertices = rest_skeleton(body)
    mesh = body.mesh
    baked = SkinnedMesh(vertices, mesh.faces, mesh.joints, mesh.weights,
                        np.tile(np.eye(4), (len(joints), 1, 1)), name="depthtrack body")
    gl = g.GLTF2.load_from_bytes(gltf_bytes(baked, joints, head_centre=head,
                                            joint_names=tuple(body.joint_names)))
    gl.asset.generator = "depthtrack export"
    blob = bytearray(gl.binary_blob())

    def add(array, typ, minmax=False):
        array = np.ascontiguousarray(array, dtype=np.float32)
        blob.extend(b"\x00" * (-len(blob) % 4))
        gl.bufferViews.append(g.BufferView(buffer=0, byteOffset=len(blob), byteLength=array.nbytes))
        blob.extend(array.tobytes())
        acc = g.Accessor(bufferView=len(gl.bufferViews) - 1, componentType=g.FLOAT,
                         count=len(array), type=typ)
        if minmax:
            acc.min = [float(v) for v in np.atleast_2d(array.T).min(1)]
            acc.max = [float(v) for v in np.atleast_2d(array.T).max(1)]
        gl.accessors.append(acc)
        return len(gl.accessors) - 1

    rotations, translation = animation_channels(body, poses)
    times = np.arange(len(poses), dtype=np.float64) / float(fps)
    a_time = add(times.reshape(-1, 1), g.SCALAR, minmax=True)   # input accessors need min/max
    samplers, channels = [], []
    names = list(body.joint_names)
    node_of = {nd.name: i for i, nd in enumerate(gl.nodes)}
    root = node_of[names[int(np.flatnonzero(np.asarray(body.parents) < 0)[0])]]
    samplers.append(g.AnimationSampler(input=a_time, output=add(translation, g.VEC3), interpolation="LINEAR"))
    channels.append(g.AnimationChannel(sampler=0, target=g.AnimationChannelTarget(node=root, path="translation")))
    for j, name in enumerate(names):
        samplers.append(g.AnimationSampler(input=a_time, output=add(rotations[:, j], g.VEC4),
                                           interpolation="LINEAR"))
        channels.append(g.AnimationChannel(sampler=len(samplers) - 1,
                                           target=g.AnimationChannelTarget(node=node_of[name], path="rotation")))
    gl.animations = [g.Animation(name=ANIMATION_NAME, samplers=samplers, channels=channels)]
    # the nodes' static transforms stay the bind pose: without the animation a viewer (or
    # depthtrack.body.gltf.load_skinned_gltf) sees the rest pose, pelvis at the origin
    blob.extend(b"\x00" * (-len(blob) % 4))
    gl.buffers[0].byteLength = len(blob)
    gl.set_binary_blob(bytes(blob))
    return gl


def write_gltf(path, body, poses, fps: float) -> Path:
    """Write the animated body as ``.glb`` (binary) or ``.gltf`` (JSON, buffer embedded).

    Parameters
    ----------
    path : path-like
        The suffix chooses the container.
    body : BodyModel
        The tracked (scaled) body.
    poses : (F, D) float
        NaN rows hold the last pose.
    fps : float
    """
    import pygltflib as g

    path = Path(path)
    gl = gltf_animated(body, poses, fps)
    if path.suffix.lower() == ".gltf":
        gl.convert_buffers(g.BufferFormat.DATAURI)
        write_text_atomic(path, gl.gltf_to_json())
    else:
        write_bytes_atomic(path, b"".join(gl.save_to_bytes()))
    return path
