# SPDX-License-Identifier: BSD-3-Clause
"""AsyncFEM: tetrahedral FEM meshes, matrices, sparse solvers, force models, single-rate and
asynchronous implicit integrators, simulation output and off-screen rendering.

Vectors are stacked 3n float64 arrays (x0 y0 z0 x1 ...), system matrices
scipy.sparse.csc_matrix, positions (n, 3) arrays, ids 0-based. Everything lives in the
compiled extension asyncfem._asyncfem and is re-exported here.
"""
import os as _os

# Idle OpenMP threads must sleep, not spin: spinning threads take the cores CHOLMOD's BLAS
# threads need (a factorization was measured 25x slower on 2 cores). The OpenMP runtime
# reads the policy once, when it is loaded with the extension below, so it is set here
# first; a policy the user set is kept. (If another module loaded the OpenMP runtime
# before asyncfem, set OMP_WAIT_POLICY=passive in the environment yourself.)
_os.environ.setdefault("OMP_WAIT_POLICY", "passive")

from ._asyncfem import *  # noqa: E402,F401,F403
from ._asyncfem import __version__, has_render  # noqa: E402,F401
