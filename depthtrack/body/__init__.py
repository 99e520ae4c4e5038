"""STAGE 1 READY -- the articulated, skinned human body model.

``from depthtrack.body import BodyModel``; ``BodyModel.default(height=1.75, mesh="full")``.

Modules:

* :mod:`.skeleton` -- the 15-joint kinematic tree, the 48-parameter pose layout
  (``POSE_NAMES``), joint limits and batched forward kinematics;
* :mod:`.rotations` -- batched rotation-vector / matrix / quaternion helpers, slerp;
* :mod:`.mesh` -- ``SkinnedMesh`` and the numpy linear-blend-skinning reference;
* :mod:`.model` -- ``BodyModel``: skeleton + mesh + dimensions, posed in batches;
* :mod:`.shape` -- ``BodyShape``: relative segment lengths, breadths and girths;
* :mod:`.gltf` -- read rigged glTF/glb skins (ours, CMU/Mixamo names), write ours;
* :mod:`.anthropometry` -- the default body's proportions, implicit surface, skin weights.
"""
from .mesh import SkinnedMesh, linear_blend_skinning
from .model import BodyModel, default_mesh_path
from .shape import BodyShape
from .skeleton import DOF, JOINTS, LOWER, PARENTS, POSE_NAMES, UPPER, forward_kinematics
from . import rotations

__all__ = ["BodyModel", "BodyShape", "SkinnedMesh", "linear_blend_skinning", "default_mesh_path", "DOF", "JOINTS",
           "LOWER", "UPPER", "PARENTS", "POSE_NAMES", "forward_kinematics", "rotations"]
