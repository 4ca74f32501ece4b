# SPDX-License-Identifier: Apache-2.0
"""voxhap: needle-insertion forces from patient volumes (docs/reference.md "Python").

World space is patient LPS in mm, forces in N, speeds in mm/s. Grids are numpy
arrays indexed [i, j, k]; Volume.index_to_world is the 4x4 affine from an array
index to world. The calls live in the extension voxhap._voxhap (python/*.cpp).
"""
from ._voxhap import *  # noqa: F401,F403
from ._voxhap import __version__  # noqa: F401
import sys as _sys

# `import voxhap.batch` as well as voxhap.batch: the submodule lives in the extension.
from ._voxhap import batch  # noqa: E402

_sys.modules[__name__ + ".batch"] = batch
