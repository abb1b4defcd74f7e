# SPDX-License-Identifier: BSD-3-Clause
"""`cmake --install build --component python` puts a package that imports on its own."""
import os
import subprocess
import sys

from conftest import BINARY_DIR


def test_installed_package_imports(tmp_path):
    cmake = os.environ.get("ASYNCFEM_CMAKE_COMMAND", "cmake")
    subprocess.run([cmake, "--install", str(BINARY_DIR), "--component", "python", "--prefix", str(tmp_path)],
                   check=True, capture_output=True)
    found = list(tmp_path.glob("lib/python3.*/dist-packages/asyncfem/__init__.py"))
    assert len(found) == 1, "expected PREFIX/lib/python3.X/dist-packages/asyncfem"
    environment = {key: value for key, value in os.environ.items() if key not in ("PYTHONPATH", "OMP_WAIT_POLICY")}
    environment["PYTHONPATH"] = str(found[0].parents[1])
    script = ("import os, asyncfem; assert asyncfem.__file__.startswith(os.environ['PYTHONPATH']); "
              "print(os.environ['OMP_WAIT_POLICY'], asyncfem.make_box_mesh(asyncfem.BoxMeshSpec()).num_elements)")
    result = subprocess.run([sys.executable, "-c", script], env=environment, cwd=tmp_path, check=True,
                            capture_output=True, text=True)
    assert result.stdout.split() == ["passive", str(4 * 4 * 4 * 6)]
