"""Re-export of :mod:`depthtrack.rotations` (kept so ``depthtrack.body.rotations`` still works).

The helpers live in the package's bottom layer so that ``io`` (the BVH reader and writer)
can use them without importing ``body``.
"""
from ..rotations import *  # noqa: F401,F403
from ..rotations import __all__  # noqa: F401
