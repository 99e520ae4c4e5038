"""Axis conventions of the exports, in one place.

Our tracks live in the OpenCV camera frame: x right, y down, z forward (metres). Tools
want an up axis; these proper rotations (determinant +1, so handedness is kept) take
camera-frame vectors to theirs: ``v_out = M @ v_camera``. The origin stays at the camera.
"""
from __future__ import annotations

import numpy as np

#: y up (glTF, BVH, Unity, Maya): 180 degrees about x -- x right, y up, z toward the camera's
#: viewer (the camera looks along -z, as a glTF camera does). Its own inverse.
Y_UP_FROM_CAMERA = np.diag([1.0, -1.0, -1.0])

#: z up (C3D, biomechanics tools, Blender's world): x right, y away from the camera
#: (its viewing direction), z up; -90 degrees about x.
Z_UP_FROM_CAMERA = np.array([[1.0, 0.0, 0.0],
                             [0.0, 0.0, 1.0],
                             [0.0, -1.0, 0.0]])

#: ``--up`` choices.
UP_AXES = {"y": Y_UP_FROM_CAMERA, "z": Z_UP_FROM_CAMERA}
