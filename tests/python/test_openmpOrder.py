# SPDX-License-Identifier: BSD-3-Clause
"""Import order and the OpenMP wait policy: asyncfem sets OMP_WAIT_POLICY=passive before the
OpenMP runtime loads; when another module loaded the runtime first (matplotlib does), the
policy comes too late and asyncfem says so at import with the fix, instead of running
several times slower silently. GNU libgomp's omp_display_env shows the policy in effect:
GOMP_SPINCOUNT '0' when passive, '300000' (spinning) when the runtime saw no policy."""
import ast
import ctypes.util
import os
import subprocess
import sys

import pytest

from conftest import SOURCE_DIR

LIBGOMP = ctypes.util.find_library("gomp")
SHOW_SPIN_COUNT = "import ctypes; ctypes.CDLL('libgomp.so.1').omp_display_env(1)"


def run_python(script, wait_policy=None):
    environment = {key: value for key, value in os.environ.items() if key != "OMP_WAIT_POLICY"}
    if wait_policy is not None:
        environment["OMP_WAIT_POLICY"] = wait_policy
    return subprocess.run([sys.executable, "-c", script], env=environment, check=True, capture_output=True,
                          text=True)


def spin_count(stderr):
    lines = [line for line in stderr.splitlines() if "GOMP_SPINCOUNT" in line]
    assert len(lines) == 1, stderr
    return lines[0].split("=")[1].strip().strip("'")


@pytest.mark.skipif(LIBGOMP is None, reason="GNU libgomp not found")
def test_runtime_loaded_first_is_warned_about_with_the_fix():
    result = run_python("import ctypes; ctypes.CDLL('libgomp.so.1'); import asyncfem; "
                        "print(asyncfem.openmp_wait_policy_too_late); " + SHOW_SPIN_COUNT)
    assert result.stdout.split() == ["True"]
    assert "OpenMPWaitPolicyWarning" in result.stderr
    assert "import asyncfem before matplotlib" in result.stderr
    assert "OMP_WAIT_POLICY=passive" in result.stderr
    assert spin_count(result.stderr) != "0"  # what the warning is about: idle threads spin


@pytest.mark.skipif(LIBGOMP is None, reason="GNU libgomp not found")
def test_asyncfem_first_makes_idle_threads_sleep_without_warning():
    result = run_python("import asyncfem, ctypes; ctypes.CDLL('libgomp.so.1'); "
                        "print(asyncfem.openmp_wait_policy_too_late); " + SHOW_SPIN_COUNT)
    assert result.stdout.split() == ["False"]
    assert "OpenMPWaitPolicyWarning" not in result.stderr
    assert spin_count(result.stderr) == "0"


@pytest.mark.skipif(LIBGOMP is None, reason="GNU libgomp not found")
def test_policy_in_the_environment_needs_no_warning():
    result = run_python("import ctypes; ctypes.CDLL('libgomp.so.1'); import asyncfem; "
                        "print(asyncfem.openmp_wait_policy_too_late); " + SHOW_SPIN_COUNT, wait_policy="passive")
    assert result.stdout.split() == ["False"]
    assert "OpenMPWaitPolicyWarning" not in result.stderr
    assert spin_count(result.stderr) == "0"


def test_matplotlib_first_is_warned_about():
    pytest.importorskip("matplotlib")
    result = run_python("import matplotlib.pyplot, asyncfem; print(asyncfem.openmp_wait_policy_too_late)")
    runtimes = run_python("import matplotlib.pyplot, asyncfem; print(asyncfem._loaded_openmp_runtimes())")
    if "libgomp" not in runtimes.stdout and "libomp" not in runtimes.stdout:
        pytest.skip("this matplotlib loads no OpenMP runtime")
    assert "OpenMPWaitPolicyWarning" in result.stderr


def test_python_examples_import_asyncfem_before_matplotlib():
    for example in sorted((SOURCE_DIR / "examples" / "python").glob("*.py")):
        imported = []
        for node in ast.parse(example.read_text()).body:
            if isinstance(node, ast.Import):
                imported += [alias.name.split(".")[0] for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module:
                imported.append(node.module.split(".")[0])
        if "matplotlib" in imported and "asyncfem" in imported:
            assert imported.index("asyncfem") < imported.index("matplotlib"), example.name
