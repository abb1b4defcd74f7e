# SPDX-License-Identifier: BSD-3-Clause
"""`pip install --no-build-isolation .` on a clean clone, with no build folder: setup.py
configures its own CMake build (Release, no utilities, no tests) and builds only the
target asyncfem_python and what it links. The clone holds the committed files only.

It builds the module from scratch (about 6 minutes on two cores), so it runs only when
ASYNCFEM_TEST_PIP_FROM_SOURCE=1; otherwise it exits 77 and ctest reports it skipped, with
that reason. test_pipInstall.py checks the install from an existing build on every run."""
import os
import subprocess
import sys
import time

import pytest

from conftest import SOURCE_DIR
from test_pipInstall import MISSING, STEP_SCRIPT, run


def test_pip_install_from_a_clean_clone(tmp_path):
    if os.environ.get("ASYNCFEM_TEST_PIP_FROM_SOURCE") != "1":
        pytest.exit("skipped: builds the module from scratch (minutes); set ASYNCFEM_TEST_PIP_FROM_SOURCE=1 to run it",
                    returncode=77)
    if MISSING:
        pytest.exit(f"skipped: {', '.join(MISSING)} not installed for {sys.executable}", returncode=77)
    clone = tmp_path / "clone"
    run(["git", "clone", "--quiet", SOURCE_DIR, clone])
    assert not (clone / "build").exists()
    venv = tmp_path / "venv"
    run([sys.executable, "-m", "venv", "--system-site-packages", venv])
    python = venv / "bin" / "python"
    environment = {key: value for key, value in os.environ.items()
                   if key not in ("PYTHONPATH", "PIP_INDEX_URL", "ASYNCFEM_BUILD_DIR")}
    environment["PIP_NO_INPUT"] = "1"
    started = time.monotonic()
    install = run([python, "-m", "pip", "install", "--no-build-isolation", "--no-index", "--no-cache-dir",
                   "--disable-pip-version-check", clone], env=environment, cwd=tmp_path)
    print(f"pip install from a clean clone: {time.monotonic() - started:.0f} s")
    assert "Successfully installed asyncfem" in install.stdout
    # Its own CMake build, below the clone's build/pip, with only the module's targets built.
    caches = list((clone / "build" / "pip").glob("**/cmake/CMakeCache.txt"))
    assert len(caches) == 1, caches
    built = caches[0].parent
    assert not (built / "bin" / "offlineSimulator").exists()
    assert "ASYNCFEM_BUILD_TESTS:BOOL=OFF" in caches[0].read_text(encoding="utf-8", errors="replace")
    result = run([python, "-c", STEP_SCRIPT], env=environment, cwd=tmp_path)
    version, steps, lowest = result.stdout.split()
    assert int(steps) == 10
    assert float(lowest) < 0.0  # the free end moved down under the pull
    assert version == subprocess.run([sys.executable, "-c", "import asyncfem; print(asyncfem.__version__)"],
                                     capture_output=True, text=True, check=True).stdout.strip()
