# SPDX-License-Identifier: BSD-3-Clause
"""Builds the asyncfem Python package with the project's own CMake, for
`pip install --no-build-isolation .` (pyproject.toml).

Which CMake build folder: $ASYNCFEM_BUILD_DIR when set, else ./build when it holds a
configured build (CMakeCache.txt), else a new one under setuptools' temporary folder. An
existing build is reused as configured (its compiler, Python and options) and only the
target asyncfem_python and what it needs is built, so after `cmake --build build` the
install compiles nothing. A new build is configured Release without utilities and tests,
for the interpreter that runs pip. setuptools' own files (build/lib..., the metadata) go
below the CMake build folder's `pip/`, so the source tree is not written to.
"""
import os
import pathlib
import re
import shutil
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

SOURCE = pathlib.Path(__file__).resolve().parent


def version():
    text = (SOURCE / "CMakeLists.txt").read_text(encoding="utf-8")
    found = re.search(r"project\(AsyncFEM\s+VERSION\s+([0-9.]+)", text)
    if not found:
        sys.exit("setup.py: no 'project(AsyncFEM VERSION x.y.z)' in CMakeLists.txt")
    return found.group(1)


def existing_build():
    """The CMake build folder to reuse, or None."""
    given = os.environ.get("ASYNCFEM_BUILD_DIR")
    if given:
        return pathlib.Path(given).resolve()
    default = SOURCE / "build"
    return default if (default / "CMakeCache.txt").is_file() else None


def run(command):
    print("asyncfem setup.py:", " ".join(str(part) for part in command), flush=True)
    subprocess.run([str(part) for part in command], check=True)


class CMakeExtension(Extension):
    """The pybind11 extension asyncfem._asyncfem, built by CMake, not by setuptools."""

    def __init__(self):
        super().__init__("asyncfem._asyncfem", sources=[])


class BuildWithCMake(build_ext):
    def build_extension(self, ext):
        build = existing_build()
        if build is None:
            build = pathlib.Path(self.build_temp).resolve() / "cmake"
        if not (build / "CMakeCache.txt").is_file():
            generator = ["-G", "Ninja"] if shutil.which("ninja") else []
            run(["cmake", "-S", SOURCE, "-B", build, *generator, "-DCMAKE_BUILD_TYPE=Release",
                 "-DASYNCFEM_WITH_PYTHON=ON", "-DASYNCFEM_BUILD_UTILITIES=OFF", "-DASYNCFEM_BUILD_TESTS=OFF",
                 f"-DPython3_EXECUTABLE={sys.executable}"])
        cache = (build / "CMakeCache.txt").read_text(encoding="utf-8", errors="replace")
        if re.search(r"^ASYNCFEM_WITH_PYTHON:BOOL=(OFF|0|FALSE|NO)$", cache, re.MULTILINE | re.IGNORECASE):
            sys.exit(f"setup.py: {build} is configured with ASYNCFEM_WITH_PYTHON=OFF; reconfigure it with "
                     "-DASYNCFEM_WITH_PYTHON=ON or set ASYNCFEM_BUILD_DIR to another build folder")
        jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL") or str(os.cpu_count() or 1)
        run(["cmake", "--build", build, "--target", "asyncfem_python", "--parallel", jobs])
        built = sorted((build / "python" / "asyncfem").glob("_asyncfem*.so"))
        if len(built) != 1:
            sys.exit(f"setup.py: expected one _asyncfem*.so in {build / 'python' / 'asyncfem'}, found {len(built)} "
                     "(is the build configured with ASYNCFEM_WITH_PYTHON=ON?)")
        target = pathlib.Path(self.get_ext_fullpath(ext.name))
        if built[0].name != target.name:
            sys.exit(f"setup.py: {built[0]} was built for another Python than {sys.executable} "
                     f"(which needs {target.name}); set ASYNCFEM_BUILD_DIR to a build for this interpreter")
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(built[0], target)


# setuptools' working files below the CMake build folder (or ./build), not in the sources.
work = (existing_build() or SOURCE / "build") / "pip"
work.mkdir(parents=True, exist_ok=True)

setup(
    version=version(),
    packages=["asyncfem"],
    package_dir={"asyncfem": "libraries/python/asyncfem"},
    ext_modules=[CMakeExtension()],
    cmdclass={"build_ext": BuildWithCMake},
    options={"build": {"build_base": str(work)}, "egg_info": {"egg_base": str(work)}},
    zip_safe=False,
)
