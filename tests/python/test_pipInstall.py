# SPDX-License-Identifier: BSD-3-Clause
"""`pip install --no-build-isolation .` into a fresh virtual environment (with the system's
NumPy and SciPy through --system-site-packages) installs a package that imports and steps
from outside the source tree. The install reuses this build folder (ASYNCFEM_BUILD_DIR),
so it compiles nothing, and --no-index makes any download an error.

Without venv, pip, setuptools or wheel (Debian's python3-venv, python3-pip,
python3-setuptools, python3-wheel; scripts/install-deps.sh installs them) the test exits
77, which ctest reports as skipped."""
import importlib.util
import os
import subprocess
import sys

import pytest

from conftest import BINARY_DIR, SOURCE_DIR

MISSING = [name for name in ("venv", "ensurepip", "pip", "setuptools", "wheel") if importlib.util.find_spec(name) is None]

STEP_SCRIPT = """
import os, sys
import numpy as np
import asyncfem as af
assert os.path.realpath(af.__file__).startswith(os.path.realpath(sys.prefix)), af.__file__
spec = af.BoxMeshSpec()
spec.size, spec.cells = [0.3, 0.1, 0.1], [3, 1, 1]
mesh = af.make_box_mesh(spec)
assembler = af.MatrixAssembler(mesh)
K = af.linear_stiffness_matrix(mesh, assembler)
M = af.mass_matrix(mesh, assembler, af.MassType.consistent)
free = af.FreeDofs.from_fixed_vertices(mesh.num_vertices, mesh.set_vertices("xmin"))
pull = np.zeros(mesh.num_dofs)
pull.reshape(-1, 3)[mesh.set_vertices("xmax"), 1] = -1.0
system = af.DynamicSystem(af.LinearForceModel(K), M, free, external_force=lambda t, u, v: pull)
integrator = af.BackwardEuler(system, 0.01)
integrator.step(10)
print(af.__version__, integrator.stats.steps, float(integrator.displacement.reshape(-1, 3)[:, 1].min()))
"""


def run(command, **keywords):
    result = subprocess.run([str(part) for part in command], capture_output=True, text=True, **keywords)
    assert result.returncode == 0, f"{command} failed:\n{result.stdout[-3000:]}\n{result.stderr[-3000:]}"
    return result


def test_pip_install_into_a_fresh_venv(tmp_path):
    if MISSING:
        pytest.exit(f"skipped: {', '.join(MISSING)} not installed for {sys.executable}", returncode=77)
    venv = tmp_path / "venv"
    run([sys.executable, "-m", "venv", "--system-site-packages", venv])
    python = venv / "bin" / "python"
    environment = {key: value for key, value in os.environ.items() if key not in ("PYTHONPATH", "PIP_INDEX_URL")}
    environment["ASYNCFEM_BUILD_DIR"] = str(BINARY_DIR)
    environment["PIP_NO_INPUT"] = "1"
    install = run([python, "-m", "pip", "install", "--no-build-isolation", "--no-index", "--no-cache-dir",
                   "--disable-pip-version-check", SOURCE_DIR], env=environment, cwd=tmp_path)
    assert "Successfully installed asyncfem" in install.stdout
    # Outside the source and build trees, without PYTHONPATH: only the venv can provide it.
    result = run([python, "-c", STEP_SCRIPT], env=environment, cwd=tmp_path)
    version, steps, lowest = result.stdout.split()
    assert version == run([sys.executable, "-c", "import asyncfem; print(asyncfem.__version__)"]).stdout.strip()
    assert int(steps) == 10
    assert float(lowest) < 0.0  # the free end moved down under the pull
    shown = run([python, "-m", "pip", "show", "asyncfem"], env=environment, cwd=tmp_path).stdout
    assert "Name: asyncfem" in shown and str(venv) in shown
