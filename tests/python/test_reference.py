# SPDX-License-Identifier: BSD-3-Clause
"""A beam run composed in Python (mesh, matrices, load, integrator stepped from Python)
equals offlineSimulator's output of the same scene bit for bit."""
import subprocess
from pathlib import Path

import numpy as np
import pytest

import asyncfem as af
from conftest import BINARY_DIR, SOURCE_DIR

FRAMES = 10  # 0.33 s: the pull and its release at 0.3 s
PULL = np.array([0.0, -40.0, 0.0])  # models/beam/*.json: pull "tip" with [0, -40, 0] N over [0, 0.3) s
PULL_END = 0.3


def offline(scene, tmp_path):
    output = tmp_path / (scene.stem + ".afsim")
    simulator = BINARY_DIR / "bin" / "offlineSimulator"
    if not simulator.exists():
        pytest.fail(f"{simulator} not built (ninja -C {BINARY_DIR} offlineSimulator)")
    subprocess.run([str(simulator), str(scene), "--frames", str(FRAMES), "--output", str(output), "-q"],
                   check=True, cwd=tmp_path)
    return af.SimulationReader(output)


def beam_system(mesh, h):
    assembler = af.MatrixAssembler(mesh)
    stiffness = af.linear_stiffness_matrix(mesh, assembler)
    mass = af.mass_matrix(mesh, assembler, af.MassType.consistent)
    free = af.FreeDofs.from_fixed_vertices(mesh.num_vertices, mesh.set_vertices("root"))
    tip = mesh.set_vertices("tip")
    load = np.zeros(mesh.num_dofs)
    load.reshape(-1, 3)[tip] = PULL / len(tip)
    # The scene layer's window rule: active at step times t with start <= t < end, each
    # bound moved down by 1e-9 h (docs/scene-format.md).
    start, end = -1e-9 * h, PULL_END - 1e-9 * h

    def pull(time, u, v):
        return load if start <= time < end else None

    return af.DynamicSystem(af.LinearForceModel(stiffness), mass, free, external_force=pull)


def compare(integrator, reader, steps_per_frame):
    assert reader.num_frames == FRAMES
    for k in range(FRAMES):
        for _ in range(steps_per_frame):
            integrator.step()  # one Python call per step, as a prototype would
        frame = reader.read_frame(k)
        assert frame.time == integrator.time
        np.testing.assert_array_equal(integrator.displacement, frame.displacement)


def test_backward_euler_equals_offline_simulator(tmp_path):
    scene = SOURCE_DIR / "models" / "beam" / "beam-single-rate.json"
    reader = offline(scene, tmp_path)
    h = 0.0016666666666666668  # the scene's integrator.timestep; 20 steps per 1/30 s frame
    mesh = af.read_mesh(SOURCE_DIR / "models" / "beam" / "beam.veg")
    compare(af.BackwardEuler(beam_system(mesh, h), h), reader, 20)


def test_async_equals_offline_simulator(tmp_path):
    scene = SOURCE_DIR / "models" / "beam" / "beam.json"
    reader = offline(scene, tmp_path)
    h = 0.008333333333333333  # 4 large steps per frame, the tip region at ratio 8
    mesh = af.read_mesh(SOURCE_DIR / "models" / "beam" / "beam.veg")
    tip = af.region_vertices(mesh, element_sets=["tip"])
    integrator = af.AsyncBackwardEuler(mesh, beam_system(mesh, h), h, [af.AsyncRegion("tip", tip, 8)])
    compare(integrator, reader, 4)


def test_the_solvers_reach_the_blas_the_module_loaded():
    """The factorizations hold OpenBLAS to one thread (dpotrf's bits depend on the count).
    In a Python process the module and its BLAS sit in a local scope, which a global symbol
    lookup does not see: the guard then did nothing, and the runs above differed from
    offlineSimulator's by up to 5e-15 on a 2-core machine."""
    if "openblas" not in Path("/proc/self/maps").read_text():
        pytest.skip("this process has no OpenBLAS (another BLAS: nothing to hold)")
    assert af.blas_threads() >= 1
