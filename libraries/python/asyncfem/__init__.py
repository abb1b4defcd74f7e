# SPDX-License-Identifier: BSD-3-Clause
"""AsyncFEM: tetrahedral FEM meshes, matrices, sparse solvers, force models, single-rate and
asynchronous implicit integrators, simulation output and off-screen rendering.

Vectors are stacked 3n float64 arrays (x0 y0 z0 x1 ...), system matrices
scipy.sparse.csc_matrix, positions (n, 3) arrays, ids 0-based. Everything lives in the
compiled extension asyncfem._asyncfem and is re-exported here.
"""
import os as _os
import warnings as _warnings


class OpenMPWaitPolicyWarning(RuntimeWarning):
    """An OpenMP runtime was loaded before asyncfem without OMP_WAIT_POLICY: its idle threads
    spin, and sparse factorizations and solves run several times slower."""


def _loaded_openmp_runtimes():
    """File names of the OpenMP runtimes (GNU libgomp, LLVM libomp, Intel libiomp) this
    process has loaded so far (Linux: from /proc/self/maps; elsewhere none are found)."""
    names = set()
    try:
        with open("/proc/self/maps", encoding="utf-8", errors="replace") as maps:
            for line in maps:
                name = line.rsplit("/", 1)[-1].strip()
                if name.startswith(("libgomp", "libomp", "libiomp")) and ".so" in name:
                    names.add(name)
    except OSError:
        pass
    return sorted(names)


# Idle OpenMP threads must sleep, not spin: spinning threads take the cores CHOLMOD's BLAS
# threads need (a factorization was measured 25x slower on 2 cores). The OpenMP runtime
# reads the policy once, when it is loaded, so it is set here, before the extension below
# loads it; a policy the user set is kept. When another module (matplotlib, for one) loaded
# the runtime first without a policy in the environment, setting it now changes nothing:
# say so, with the fix, instead of running several times slower silently.
_early_runtimes = [] if "OMP_WAIT_POLICY" in _os.environ else _loaded_openmp_runtimes()
_os.environ.setdefault("OMP_WAIT_POLICY", "passive")
#: True when the OpenMP runtime was loaded before asyncfem without OMP_WAIT_POLICY, so
#: its threads spin while idle (see OpenMPWaitPolicyWarning).
openmp_wait_policy_too_late = bool(_early_runtimes)
if openmp_wait_policy_too_late:
    _warnings.warn(
        "asyncfem: the OpenMP runtime (" + ", ".join(_early_runtimes) + ") was loaded by a module imported "
        "before asyncfem (matplotlib, for one) without OMP_WAIT_POLICY, so its idle threads spin and "
        "factorizations and solves can run 3-4x slower. Fix: import asyncfem before matplotlib and other "
        "modules that load OpenMP, or run with OMP_WAIT_POLICY=passive in the environment "
        "(OMP_WAIT_POLICY=passive python3 script.py).",
        OpenMPWaitPolicyWarning,
        stacklevel=1,
    )

from ._asyncfem import *  # noqa: E402,F401,F403
from ._asyncfem import __version__, has_render  # noqa: E402,F401
