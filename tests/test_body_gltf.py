"""glTF skins: our own files round-trip; foreign (Mixamo-style) rigs map onto our skeleton."""
import numpy as np
import pygltflib as g
import pytest

from depthtrack.body import BodyModel
from depthtrack.body.gltf import (GLTF_TO_MODEL, gltf_bytes, load_skinned_gltf, mixamo_names,
                                  normalise_name)
from depthtrack.body.rotations import rotvec_to_matrix
from depthtrack.errors import InputError


@pytest.fixture(scope="module")
def body():
    return BodyModel.default(mesh="decimated")


def _dense(joints, weights):
    w = np.zeros((len(joints), 15))
    np.add.at(w, (np.repeat(np.arange(len(joints)), joints.shape[1]), joints.reshape(-1).astype(int)),
              weights.reshape(-1))
    return w


def test_round_trip_with_mixamo_names(body, tmp_path):
    joints = body.joint_positions(body.default_pose())  # contract order
    skeleton = body.world_transforms(body.default_pose())[:, :3, 3]
    path = tmp_path / "renamed.glb"
    path.write_bytes(gltf_bytes(body.mesh, skeleton, head_centre=joints[0], joint_names=mixamo_names()))
    loaded = load_skinned_gltf(path)
    assert loaded.source_joints[3] == "mixamorig:LeftArm"
    np.testing.assert_allclose(loaded.mesh.vertices, body.mesh.vertices, atol=1e-6)
    np.testing.assert_array_equal(loaded.mesh.faces, body.faces)
    np.testing.assert_allclose(_dense(loaded.mesh.joints, loaded.mesh.weights),
                               _dense(body.mesh.joints, body.mesh.weights), atol=1e-6)
    np.testing.assert_allclose(loaded.offsets, body.offsets, atol=1e-6)
    np.testing.assert_allclose(loaded.head_offset, body.head_offset, atol=1e-6)
    other = BodyModel.from_gltf(path)
    pose = body.clip(np.random.default_rng(0).normal(scale=0.5, size=(2, 48)))
    np.testing.assert_allclose(other.posed_vertices(pose), body.posed_vertices(pose), atol=1e-5)
    np.testing.assert_allclose(other.joint_positions(pose), body.joint_positions(pose), atol=1e-6)


def _foreign_rig(body):
    """A Mixamo-like export: cm units under a rotated, scaled Armature node, extra bones
    (Spine1, Head, clavicles, toes) carrying weight, joints listed in a shuffled order."""
    P = body.world_transforms(body.default_pose())[:, :3, 3] @ GLTF_TO_MODEL.T  # glTF world, metres
    head_world = body.joint_positions(body.default_pose())[0] @ GLTF_TO_MODEL.T
    arm_rot = rotvec_to_matrix([np.pi / 2, 0, 0])
    armature = np.eye(4)
    armature[:3, :3] = 0.01 * arm_rot
    to_local = lambda x: (np.asarray(x) @ arm_rot) / 0.01  # world metres -> armature cm

    names = {  # ours -> Mixamo
        "pelvis": "Hips", "spine": "Spine", "neck": "Neck", "l_shoulder": "LeftArm", "l_elbow": "LeftForeArm",
        "l_wrist": "LeftHand", "r_shoulder": "RightArm", "r_elbow": "RightForeArm", "r_wrist": "RightHand",
        "l_hip": "LeftUpLeg", "l_knee": "LeftLeg", "l_ankle": "LeftFoot", "r_hip": "RightUpLeg",
        "r_knee": "RightLeg", "r_ankle": "RightFoot"}
    pos = {names[n]: P[i] for i, n in enumerate(body.joint_names)}
    pos["Spine1"] = 0.5 * (pos["Spine"] + pos["Neck"])
    pos["Head"] = 0.5 * (pos["Neck"] + head_world)
    pos["LeftShoulder"] = 0.5 * (pos["Spine1"] + pos["LeftArm"])
    pos["RightShoulder"] = 0.5 * (pos["Spine1"] + pos["RightArm"])
    pos["LeftToeBase"] = pos["LeftFoot"] + [0, -0.05, 0.12]
    parent = {"Hips": None, "Spine": "Hips", "Spine1": "Spine", "Neck": "Spine1", "Head": "Neck",
              "LeftShoulder": "Spine1", "LeftArm": "LeftShoulder", "LeftForeArm": "LeftArm",
              "LeftHand": "LeftForeArm", "RightShoulder": "Spine1", "RightArm": "RightShoulder",
              "RightForeArm": "RightArm", "RightHand": "RightForeArm", "LeftUpLeg": "Hips",
              "LeftLeg": "LeftUpLeg", "LeftFoot": "LeftLeg", "LeftToeBase": "LeftFoot",
              "RightUpLeg": "Hips", "RightLeg": "RightUpLeg", "RightFoot": "RightLeg"}
    order = sorted(parent)
    order = order[::2] + order[1::2]  # a skin order unlike ours
    index = {n: i for i, n in enumerate(order)}

    # weights: our influences, with part of each moved onto the extra bones
    w = _dense(body.mesh.joints, body.mesh.weights)
    fw = np.zeros((len(w), len(order)))
    for i, n in enumerate(body.joint_names):
        fw[:, index[names[n]]] = w[:, i]
    every_other = np.arange(len(w)) % 2 == 0
    for extra, host in (("Spine1", "Spine"), ("Head", "Neck"), ("LeftToeBase", "LeftFoot")):
        fw[every_other, index[extra]] = fw[every_other, index[host]]
        fw[every_other, index[host]] = 0.0
    top = np.argsort(-fw, axis=1)[:, :4]
    tw = np.take_along_axis(fw, top, 1)
    tw /= tw.sum(1, keepdims=True)

    verts = to_local(body.mesh.vertices.astype(np.float64) @ GLTF_TO_MODEL.T).astype(np.float32)
    local = {n: to_local(p) for n, p in pos.items()}
    blobs, views, accs = [], [], []

    def add(arr, comp, typ):
        data = np.ascontiguousarray(arr).tobytes()
        views.append(g.BufferView(buffer=0, byteOffset=sum(len(b) for b in blobs), byteLength=len(data)))
        acc = g.Accessor(bufferView=len(views) - 1, componentType=comp, count=len(arr), type=typ)
        if typ == g.VEC3:
            acc.min, acc.max = arr.min(0).tolist(), arr.max(0).tolist()
        accs.append(acc)
        blobs.append(data + b"\0" * (-len(data) % 4))
        return len(accs) - 1

    a_pos = add(verts, g.FLOAT, g.VEC3)
    a_j = add(top.astype(np.uint8), g.UNSIGNED_BYTE, g.VEC4)
    a_w = add(tw.astype(np.float32), g.FLOAT, g.VEC4)
    a_i = add(body.faces.astype(np.uint16).reshape(-1, 1), g.UNSIGNED_SHORT, g.SCALAR)
    ibm = np.tile(np.eye(4), (len(order), 1, 1))
    ibm[:, :3, 3] = -np.array([local[n] for n in order])
    a_ibm = add(ibm.transpose(0, 2, 1).reshape(-1, 16).astype(np.float32), g.FLOAT, g.MAT4)
    nodes = [g.Node(name="mixamorig:" + n, children=[],
                    translation=(local[n] - (local[parent[n]] if parent[n] else 0)).tolist()) for n in order]
    for n in order:
        if parent[n]:
            nodes[index[parent[n]]].children.append(index[n])
    qx = np.sin(np.pi / 4)
    nodes.append(g.Node(name="Armature", children=[index["Hips"]], rotation=[qx, 0, 0, np.cos(np.pi / 4)],
                        scale=[0.01, 0.01, 0.01]))
    nodes.append(g.Node(name="Body", mesh=0, skin=0))
    gl = g.GLTF2(scene=0, scenes=[g.Scene(nodes=[len(nodes) - 2, len(nodes) - 1])], nodes=nodes,
                 meshes=[g.Mesh(primitives=[g.Primitive(attributes=g.Attributes(POSITION=a_pos, JOINTS_0=a_j,
                                                                                 WEIGHTS_0=a_w), indices=a_i)])],
                 skins=[g.Skin(joints=list(range(len(order))), inverseBindMatrices=a_ibm)],
                 accessors=accs, bufferViews=views, buffers=[g.Buffer(byteLength=sum(len(b) for b in blobs))])
    gl.set_binary_blob(b"".join(blobs))
    return gl


def test_foreign_mixamo_rig_maps_onto_our_skeleton(body, tmp_path):
    path = tmp_path / "mixamo.glb"
    _foreign_rig(body).save_binary(str(path))
    loaded = load_skinned_gltf(path)
    # cm under a rotated armature come back as metres in our frame
    np.testing.assert_allclose(loaded.mesh.vertices, body.mesh.vertices, atol=1e-5)
    np.testing.assert_allclose(loaded.offsets, body.offsets, atol=1e-5)
    # weights of Spine1 / Head / toes went back to spine / neck / ankle
    np.testing.assert_allclose(_dense(loaded.mesh.joints, loaded.mesh.weights),
                               _dense(body.mesh.joints, body.mesh.weights), atol=1e-5)
    # no head_centre node: the head centre is estimated from the neck's vertices
    assert np.linalg.norm(loaded.head_offset - body.head_offset) < 0.03
    foreign = BodyModel.from_gltf(path)
    pose = body.clip(np.random.default_rng(1).normal(scale=0.5, size=(3, 48)))
    np.testing.assert_allclose(foreign.posed_vertices(pose), body.posed_vertices(pose), atol=1e-4)
    assert foreign.height == pytest.approx(np.ptp(body.rest_vertices[:, 1]), abs=1e-4)  # its own extent
    assert BodyModel.from_gltf(path, height=1.6).height == pytest.approx(1.6, abs=1e-9)


def test_gltf_json_with_embedded_buffer(body, tmp_path):
    gl = _foreign_rig(body)
    gl.convert_buffers(g.BufferFormat.DATAURI)
    path = tmp_path / "rig.gltf"
    gl.save_json(str(path))
    np.testing.assert_allclose(load_skinned_gltf(path).mesh.vertices, body.mesh.vertices, atol=1e-5)


def test_alias_normalisation():
    assert normalise_name("mixamorig:LeftForeArm") == "leftforearm"
    assert normalise_name("Left_Fore-Arm") == "leftforearm"
    assert normalise_name("l_elbow") == "lelbow"


def test_not_gltf(tmp_path):
    path = tmp_path / "body.glb"
    path.write_text("this is not a mesh\n")
    with pytest.raises(InputError, match="not a glTF file"):
        load_skinned_gltf(path)
    with pytest.raises(InputError, match="no such file"):
        load_skinned_gltf(tmp_path / "missing.glb")
    broken = tmp_path / "broken.gltf"
    broken.write_text("{ not json")
    with pytest.raises(InputError, match="not a readable glTF"):
        load_skinned_gltf(broken)


def test_mesh_without_skin(tmp_path):
    import trimesh
    path = tmp_path / "box.glb"
    path.write_bytes(trimesh.creation.box().export(file_type="glb"))
    with pytest.raises(InputError, match="no skinned mesh"):
        load_skinned_gltf(path)


def test_unmappable_joints_are_named(body, tmp_path):
    gl = _foreign_rig(body)
    for node in gl.nodes:
        if node.name in ("mixamorig:LeftForeArm", "mixamorig:RightUpLeg"):
            node.name = node.name.replace("mixamorig:", "Bone_")
    path = tmp_path / "odd.glb"
    gl.save_binary(str(path))
    with pytest.raises(InputError) as err:
        load_skinned_gltf(path)
    message = str(err.value)
    assert "missing: l_elbow, r_hip" in message and "\n" not in message
