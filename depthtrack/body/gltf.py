"""Read and write rigged body meshes as glTF 2.0 (``.glb`` / ``.gltf``) skins.

Reading accepts any skinned mesh whose joint names map onto our skeleton: our own
names (``pelvis``, ``l_elbow``...) and the common CMU / Mixamo / VRM / Unreal names
(``Hips``, ``Spine``, ``Neck``, ``LeftArm``, ``LeftForeArm``, ``LeftHand``,
``LeftUpLeg``, ``LeftLeg``, ``LeftFoot``..., with any ``prefix:`` such as
``mixamorig:``). Joints that do not map (fingers, toes, clavicles, extra spine
bones, the head bone) hand their weights to their nearest mapped ancestor.

The file's current node pose (normally its bind pose) becomes the body's zero
pose: the surface is skinned there with the file's own matrices, converted from
glTF's frame (y up, facing +z, +x = model's left) to our model frame (y down,
facing -z, +x = left) by a 180 degree turn about x, and moved so the pelvis joint
is at the origin. Our rest frames are axis-aligned, so the inverse bind matrices
become pure translations.

The contract point "head" (head centre) is read from a node named ``head_centre``
when the file has one (ours do); otherwise it is estimated from the vertices that
follow the neck: the middle of the top 0.13 H (Winter's head height) of them.
"""
from __future__ import annotations

import base64
import re
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError
from .mesh import SkinnedMesh
from .skeleton import JOINTS, JOINT_ID, NUM_JOINTS, PARENTS

#: glTF (y up, facing +z) <-> model frame (y down, facing -z): 180 degrees about x.
GLTF_TO_MODEL = np.diag([1.0, -1.0, -1.0])

_COMPONENT = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16,
              5125: np.uint32, 5126: np.float32}
_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}

#: Accepted names per joint, normalised (lower case, no separators, prefix before ':' dropped),
#: in order of preference.
JOINT_ALIASES = {
    "pelvis": ["pelvis", "hips", "hip"],
    "spine": ["spine", "spine01", "lowerback", "abdomen", "spine1"],
    "neck": ["neck", "neck01", "neck1"],
    "l_shoulder": ["lshoulder", "leftarm", "leftupperarm", "upperarml", "lupperarm", "larm", "lshldr"],
    "l_elbow": ["lelbow", "leftforearm", "leftlowerarm", "lowerarml", "lforearm", "llowerarm"],
    "l_wrist": ["lwrist", "lefthand", "handl", "lhand"],
    "r_shoulder": ["rshoulder", "rightarm", "rightupperarm", "upperarmr", "rupperarm", "rarm", "rshldr"],
    "r_elbow": ["relbow", "rightforearm", "rightlowerarm", "lowerarmr", "rforearm", "rlowerarm"],
    "r_wrist": ["rwrist", "righthand", "handr", "rhand"],
    "l_hip": ["lhip", "leftupleg", "leftupperleg", "thighl", "lthigh", "lupleg"],
    "l_knee": ["lknee", "leftleg", "leftlowerleg", "calfl", "lcalf", "lshin"],
    "l_ankle": ["lankle", "leftfoot", "footl", "lfoot"],
    "r_hip": ["rhip", "rightupleg", "rightupperleg", "thighr", "rthigh", "rupleg"],
    "r_knee": ["rknee", "rightleg", "rightlowerleg", "calfr", "rcalf", "rshin"],
    "r_ankle": ["rankle", "rightfoot", "footr", "rfoot"],
}

#: Mixamo joint names of our skeleton (with the "mixamorig:" prefix added by :func:`mixamo_names`).
MIXAMO_NAMES = ("Hips", "Spine", "Neck", "LeftArm", "LeftForeArm", "LeftHand",
                "RightArm", "RightForeArm", "RightHand", "LeftUpLeg", "LeftLeg", "LeftFoot",
                "RightUpLeg", "RightLeg", "RightFoot")


def mixamo_names(prefix="mixamorig:"):
    """Our 15 joints under their Mixamo names, ``(J,)`` tuple of str."""
    return tuple(prefix + n for n in MIXAMO_NAMES)


def normalise_name(name: str) -> str:
    """Joint name in the form the alias table uses: ``"mixamorig:Left_Arm" -> "leftarm"``."""
    base = (name or "").rsplit(":", 1)[-1]
    return re.sub(r"[\s_\-.]", "", base).lower()


@dataclass(frozen=True)
class LoadedBody:
    """What :func:`load_skinned_gltf` returns.

    mesh : SkinnedMesh (model frame, pelvis at the origin, zero pose = file's pose);
    offsets : (J, 3) bone offsets; head_offset : (3,) head centre in the neck frame;
    source_joints : (J,) the file's joint names used for ours.
    """

    mesh: SkinnedMesh
    offsets: np.ndarray
    head_offset: np.ndarray
    source_joints: tuple


# ---------------------------------------------------------------------------- reading

def _buffer_bytes(gltf, index, path):
    buf = gltf.buffers[index]
    if buf.uri is None:
        blob = gltf.binary_blob()
        if blob is None:
            raise InputError(path, f"glTF buffer {index} has no data")
        return blob
    if buf.uri.startswith("data:"):
        return base64.b64decode(buf.uri.split(",", 1)[1])
    file = Path(path).parent / buf.uri
    try:
        return file.read_bytes()
    except OSError as exc:
        raise InputError(path, f"cannot read glTF buffer {buf.uri}: {exc.strerror}") from None


def _read_accessor(gltf, index, path, cache):
    acc = gltf.accessors[index]
    dtype = np.dtype(_COMPONENT[acc.componentType]).newbyteorder("<")
    width = _WIDTH[acc.type]
    if acc.bufferView is None:
        return np.zeros((acc.count, width), dtype=np.float64)
    view = gltf.bufferViews[acc.bufferView]
    if view.buffer not in cache:
        cache[view.buffer] = _buffer_bytes(gltf, view.buffer, path)
    data = cache[view.buffer]
    start = (view.byteOffset or 0) + (acc.byteOffset or 0)
    item = dtype.itemsize * width
    stride = view.byteStride or item
    if acc.type in ("MAT2", "MAT3") and dtype.itemsize < 4:
        raise InputError(path, "padded small-integer matrices are not supported")
    needed = start + stride * (acc.count - 1) + item if acc.count else start
    if needed > len(data):
        raise InputError(path, f"glTF accessor {index} runs past the end of its buffer")
    raw = np.frombuffer(data, dtype=np.uint8, count=needed - start, offset=start) if acc.count else \
        np.zeros(0, np.uint8)
    if stride == item:
        out = np.frombuffer(raw.tobytes(), dtype=dtype).reshape(acc.count, width)
    else:
        rows = np.lib.stride_tricks.as_strided(raw, shape=(acc.count, item), strides=(stride, 1))
        out = np.frombuffer(np.ascontiguousarray(rows).tobytes(), dtype=dtype).reshape(acc.count, width)
    out = out.astype(np.float64) if dtype.kind == "f" else out
    if acc.normalized and dtype.kind in "iu":
        out = out.astype(np.float64) / np.iinfo(dtype).max
    return out


def _node_local(node):
    if node.matrix is not None and len(node.matrix) == 16:
        return np.array(node.matrix, dtype=np.float64).reshape(4, 4).T  # column-major
    m = np.eye(4)
    if node.rotation is not None:
        x, y, z, w = node.rotation
        from .rotations import quat_to_matrix
        m[:3, :3] = quat_to_matrix(np.array([x, y, z, w], float))
    if node.scale is not None:
        m[:3, :3] = m[:3, :3] * np.asarray(node.scale, float)[None, :]
    if node.translation is not None:
        m[:3, 3] = node.translation
    return m


def _node_worlds(gltf):
    n = len(gltf.nodes)
    parent = np.full(n, -1)
    for i, node in enumerate(gltf.nodes):
        for c in node.children or []:
            parent[c] = i
    world = [None] * n

    def get(i, depth=0):
        if world[i] is None:
            if depth > n:
                raise ValueError("cycle")
            local = _node_local(gltf.nodes[i])
            world[i] = local if parent[i] < 0 else get(parent[i], depth + 1) @ local
        return world[i]

    return np.stack([get(i) for i in range(n)]) if n else np.zeros((0, 4, 4)), parent


def _map_joints(names):
    """Our joint index -> position in ``names`` (or -1)."""
    norm = [normalise_name(nm) for nm in names]
    found = np.full(NUM_JOINTS, -1)
    for j, joint in enumerate(JOINTS):
        for alias in JOINT_ALIASES[joint]:
            if alias in norm:
                found[j] = norm.index(alias)
                break
    return found


def load_skinned_gltf(path) -> LoadedBody:
    """Read a rigged body mesh from a ``.glb`` / ``.gltf`` file.

    Raises
    ------
    InputError
        The file is missing or not glTF, has no skinned triangle mesh, or its joints
        cannot be mapped onto ours (the message names the missing joints).
    """
    import pygltflib

    path = Path(path)
    if not path.is_file():
        raise InputError(path, "no such file")
    head = path.read_bytes()[:64]
    is_glb = head[:4] == b"glTF"
    if not is_glb and not head.lstrip().startswith(b"{"):
        raise InputError(path, "not a glTF file (expected a .glb or a .gltf JSON file)")
    try:
        with warnings.catch_warnings():      # pygltflib warns on stderr about what we refuse below
            warnings.simplefilter("ignore")
            gltf = pygltflib.GLTF2().load_binary(str(path)) if is_glb else pygltflib.GLTF2().load_json(str(path))
    except Exception as exc:  # pygltflib raises assorted errors on malformed files
        raise InputError(path, f"not a readable glTF file ({type(exc).__name__}: {exc})") from None
    if gltf is None or not gltf.nodes:
        raise InputError(path, "glTF file has no nodes")
    mesh_nodes = [i for i, nd in enumerate(gltf.nodes) if nd.mesh is not None and nd.skin is not None]
    if not mesh_nodes or not gltf.skins:
        raise InputError(path, "glTF file has no skinned mesh (no skin with joints)")
    try:
        return _load(gltf, mesh_nodes[0], path)
    except InputError:
        raise
    except (IndexError, KeyError, ValueError, TypeError, AttributeError) as exc:
        raise InputError(path, f"malformed glTF skin ({type(exc).__name__}: {exc})") from None


def _load(gltf, mesh_node, path):
    cache = {}
    node = gltf.nodes[mesh_node]
    skin = gltf.skins[node.skin]
    skin_joints = list(skin.joints)
    names = [gltf.nodes[j].name or "" for j in skin_joints]
    ours = _map_joints(names)
    missing = [JOINTS[j] for j in range(NUM_JOINTS) if ours[j] < 0]
    if missing:
        raise InputError(path, "skin joints cannot be mapped onto the body model; missing: "
                               + ", ".join(missing))
    worlds, parent = _node_worlds(gltf)
    if skin.inverseBindMatrices is not None:
        ibm = _read_accessor(gltf, skin.inverseBindMatrices, path, cache).reshape(-1, 4, 4).transpose(0, 2, 1)
    else:
        ibm = np.broadcast_to(np.eye(4), (len(skin_joints), 4, 4))
    if len(ibm) != len(skin_joints):
        raise InputError(path, "skin has a different number of joints and inverse bind matrices")
    joint_skin = worlds[skin_joints] @ ibm  # mesh space -> world, per joint, at the file's pose

    # each file joint -> our joint: itself if mapped, else nearest mapped ancestor, else pelvis
    node_to_ours = {skin_joints[ours[j]]: j for j in range(NUM_JOINTS)}
    remap = np.empty(len(skin_joints), dtype=np.int64)
    for k, nd in enumerate(skin_joints):
        cur, target = nd, None
        while cur >= 0 and target is None:
            target = node_to_ours.get(cur)
            cur = parent[cur]
        remap[k] = JOINT_ID["pelvis"] if target is None else target

    verts, faces, infl_j, infl_w = [], [], [], []
    base = 0
    for prim in gltf.meshes[node.mesh].primitives:
        if prim.mode not in (None, 4):
            continue  # only triangle lists carry a surface
        attrs = prim.attributes
        if attrs.POSITION is None or attrs.JOINTS_0 is None or attrs.WEIGHTS_0 is None:
            raise InputError(path, "skinned mesh primitive lacks POSITION, JOINTS_0 or WEIGHTS_0")
        pos = _read_accessor(gltf, attrs.POSITION, path, cache)
        js = [_read_accessor(gltf, attrs.JOINTS_0, path, cache).astype(np.int64)]
        ws = [_read_accessor(gltf, attrs.WEIGHTS_0, path, cache)]
        if getattr(attrs, "JOINTS_1", None) is not None and getattr(attrs, "WEIGHTS_1", None) is not None:
            js.append(_read_accessor(gltf, attrs.JOINTS_1, path, cache).astype(np.int64))
            ws.append(_read_accessor(gltf, attrs.WEIGHTS_1, path, cache))
        jf, wf = np.concatenate(js, 1), np.concatenate(ws, 1)
        if jf.max(initial=0) >= len(skin_joints):
            raise InputError(path, "JOINTS_0 refers to a joint the skin does not have")
        if prim.indices is not None:
            idx = _read_accessor(gltf, prim.indices, path, cache).reshape(-1).astype(np.int64)
        else:
            idx = np.arange(len(pos))
        if len(idx) % 3 or (len(idx) and idx.max() >= len(pos)):
            raise InputError(path, "triangle indices are malformed")
        # skin at the file's pose: sum_k w_k * (world_k @ ibm_k) @ v
        wsum = wf.sum(1, keepdims=True)
        wn = wf / np.where(wsum > 0, wsum, 1.0)
        m = np.einsum("vk,vkij->vij", wn, joint_skin[jf])
        verts.append(np.einsum("vij,vj->vi", m[:, :3, :3], pos) + m[:, :3, 3])
        faces.append(idx.reshape(-1, 3) + base)
        # merge influences per our joint, keep the 4 strongest
        acc = np.zeros((len(pos), NUM_JOINTS))
        np.add.at(acc, (np.repeat(np.arange(len(pos)), jf.shape[1]), remap[jf].reshape(-1)), wn.reshape(-1))
        order = np.argsort(-acc, axis=1)[:, :4]
        w4 = np.take_along_axis(acc, order, 1)
        w4 = np.where(w4.sum(1, keepdims=True) > 0, w4, np.array([1.0, 0, 0, 0]))
        infl_j.append(order)
        infl_w.append(w4 / w4.sum(1, keepdims=True))
        base += len(pos)
    if not verts:
        raise InputError(path, "skinned mesh has no triangles")
    vertices = np.concatenate(verts) @ GLTF_TO_MODEL.T
    joints_pos = worlds[[skin_joints[ours[j]] for j in range(NUM_JOINTS)], :3, 3] @ GLTF_TO_MODEL.T
    origin = joints_pos[JOINT_ID["pelvis"]].copy()
    vertices -= origin
    joints_pos -= origin
    joints = np.concatenate(infl_j)
    weights = np.concatenate(infl_w)

    head_nodes = [i for i, nd in enumerate(gltf.nodes) if normalise_name(nd.name) == "headcentre"]
    if head_nodes:
        head = worlds[head_nodes[0], :3, 3] @ GLTF_TO_MODEL.T - origin
    else:
        head = _estimate_head(vertices, joints, weights, joints_pos)
    offsets = np.zeros((NUM_JOINTS, 3))
    offsets[1:] = joints_pos[1:] - joints_pos[PARENTS[1:]]
    inverse_bind = np.tile(np.eye(4), (NUM_JOINTS, 1, 1))
    inverse_bind[:, :3, 3] = -joints_pos
    mesh = SkinnedMesh(vertices, np.concatenate(faces), joints, weights, inverse_bind, name=path.name)
    return LoadedBody(mesh, offsets, head - joints_pos[JOINT_ID["neck"]],
                      tuple(names[ours[j]] for j in range(NUM_JOINTS)))


def _estimate_head(vertices, joints, weights, joints_pos):
    """Head centre ``(3,)`` from the vertices that mostly follow the neck."""
    dominant = joints[np.arange(len(joints)), np.argmax(weights, 1)]
    neck = JOINT_ID["neck"]
    sel = vertices[(dominant == neck) & (vertices[:, 1] < joints_pos[neck, 1])]
    if len(sel) == 0:
        return joints_pos[neck] + np.array([0.0, -0.1, 0.0])
    height = vertices[:, 1].max() - vertices[:, 1].min()
    top = sel[:, 1].min()
    cap = sel[sel[:, 1] < top + 0.13 * height]
    centre = cap.mean(0)
    centre[1] = top + 0.5 * 0.13 * height
    return centre


# ---------------------------------------------------------------------------- writing

def _pad4(b: bytes) -> bytes:
    return b + b"\x00" * (-len(b) % 4)


def gltf_bytes(mesh: SkinnedMesh, joint_positions, head_centre=None, joint_names=JOINTS,
               normals=True) -> bytes:
    """A binary glTF (``.glb``) of a skinned body mesh, as bytes.

    Parameters
    ----------
    mesh : SkinnedMesh
        Model-frame bind-pose surface with our 15-joint skin.
    joint_positions : (J, 3) float
        Model-frame joint positions at the bind pose (our zero pose).
    head_centre : (3,) float or None
        Written as a node ``head_centre`` under the neck.
    joint_names : (J,) str
        Node names for our joints (e.g. :func:`mixamo_names`).
    """
    import pygltflib as g

    to_gltf = GLTF_TO_MODEL  # its own inverse
    jp = np.asarray(joint_positions, dtype=np.float64) @ to_gltf.T
    verts = (mesh.vertices.astype(np.float64) @ to_gltf.T).astype(np.float32)
    blobs, views, accessors = [], [], []
    offset = 0

    def add(array, comp, typ, target=None, minmax=False):
        nonlocal offset
        data = _pad4(np.ascontiguousarray(array).tobytes())
        views.append(g.BufferView(buffer=0, byteOffset=offset, byteLength=len(np.ascontiguousarray(array).tobytes()),
                                  target=target))
        acc = g.Accessor(bufferView=len(views) - 1, componentType=comp, count=len(array), type=typ)
        if minmax:
            acc.min = [float(v) for v in array.min(0)]
            acc.max = [float(v) for v in array.max(0)]
        accessors.append(acc)
        blobs.append(data)
        offset += len(data)
        return len(accessors) - 1

    a_pos = add(verts, g.FLOAT, g.VEC3, g.ARRAY_BUFFER, minmax=True)
    attrs = dict(POSITION=a_pos)
    if normals:
        nrm = (mesh.vertex_normals().astype(np.float64) @ to_gltf.T).astype(np.float32)
        attrs["NORMAL"] = add(nrm, g.FLOAT, g.VEC3, g.ARRAY_BUFFER)
    attrs["JOINTS_0"] = add(mesh.joints.astype(np.uint16), g.UNSIGNED_SHORT, g.VEC4, g.ARRAY_BUFFER)
    attrs["WEIGHTS_0"] = add(mesh.weights.astype(np.float32), g.FLOAT, g.VEC4, g.ARRAY_BUFFER)
    a_idx = add(mesh.faces.astype(np.uint32).reshape(-1, 1), g.UNSIGNED_INT, g.SCALAR, g.ELEMENT_ARRAY_BUFFER)
    ibm = np.tile(np.eye(4), (NUM_JOINTS, 1, 1))
    ibm[:, :3, 3] = -jp
    a_ibm = add(ibm.transpose(0, 2, 1).reshape(NUM_JOINTS, 16).astype(np.float32), g.FLOAT, g.MAT4)

    nodes = []
    for j in range(NUM_JOINTS):
        t = jp[j] if PARENTS[j] < 0 else jp[j] - jp[PARENTS[j]]
        nodes.append(g.Node(name=joint_names[j], translation=[float(v) for v in t], children=[]))
    for j in range(1, NUM_JOINTS):
        nodes[PARENTS[j]].children.append(j)
    if head_centre is not None:
        hc = np.asarray(head_centre, float) @ to_gltf.T - jp[JOINT_ID["neck"]]
        nodes.append(g.Node(name="head_centre", translation=[float(v) for v in hc]))
        nodes[JOINT_ID["neck"]].children.append(len(nodes) - 1)
    nodes.append(g.Node(name="body", mesh=0, skin=0))
    mesh_node = len(nodes) - 1
    gl = g.GLTF2(
        asset=g.Asset(generator="depthtrack tools/make_body_mesh.py", version="2.0"),
        scene=0,
        scenes=[g.Scene(nodes=[JOINT_ID["pelvis"], mesh_node])],
        nodes=nodes,
        meshes=[g.Mesh(name=mesh.name, primitives=[g.Primitive(attributes=g.Attributes(**attrs),
                                                                indices=a_idx, mode=g.TRIANGLES)])],
        skins=[g.Skin(name="body", joints=list(range(NUM_JOINTS)), inverseBindMatrices=a_ibm,
                      skeleton=JOINT_ID["pelvis"])],
        accessors=accessors,
        bufferViews=views,
        buffers=[g.Buffer(byteLength=offset)],
    )
    gl.set_binary_blob(b"".join(blobs))
    return b"".join(gl.save_to_bytes())


def write_skinned_gltf(path, mesh: SkinnedMesh, joint_positions, head_centre=None, joint_names=JOINTS):
    """Write :func:`gltf_bytes` to ``path`` atomically."""
    from ..io.atomic import write_bytes_atomic
    write_bytes_atomic(path, gltf_bytes(mesh, joint_positions, head_centre, joint_names))
