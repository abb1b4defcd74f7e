# SPDX-License-Identifier: BSD-3-Clause
"""A NaN from a force model written in Python (docs/robustness.md, "Faults, counted"): the
step stops with af.NumericalError naming the time of the step and the vertex the NaN came
from (not the first DOF it spread to), the state stays at the start of that step, and a
.afsim file written frame by frame keeps only the finite frames before it."""
import re

import numpy as np
import pytest

import asyncfem as af
from conftest import linear_system, small_box
from test_forceModels import PythonLinearModel

BAD_VERTEX = 7
STEPS_PER_FRAME = 5
FAULT_CALL = 23  # the force evaluation that returns the NaN: in frame 2 (each step evaluates twice or more)


class NaNAfterSomeCalls(PythonLinearModel):
    """f_int = K u written in Python (declared nonlinear, so that every step calls it), whose
    y force on BAD_VERTEX becomes NaN from the FAULT_CALL-th evaluation on."""

    def is_linear(self):
        return False

    def internal_forces(self, u):
        forces = super().internal_forces(u)
        if self.calls >= FAULT_CALL:
            forces[3 * BAD_VERTEX + 1] = np.nan
        return forces


@pytest.mark.parametrize("integrator", ["backward_euler", "trapezoidal"])
def test_nan_from_a_python_force_model_names_time_and_vertex(tmp_path, integrator):
    mesh = small_box(cells=4)
    pull = np.zeros(mesh.num_dofs)
    pull.reshape(-1, 3)[mesh.set_vertices("xmax")] = [0.0, -5.0, 0.0]
    system, stiffness, _ = linear_system(mesh, external_force=lambda t, u, v: pull)
    model = NaNAfterSomeCalls(stiffness)
    system.force_model = model
    h = 0.01
    options = af.IntegratorOptions()
    options.max_iterations = 3  # Newton: more evaluations per step
    stepper = (af.BackwardEuler if integrator == "backward_euler" else af.Trapezoidal)(system, h, options)
    path = tmp_path / "nan.afsim"
    header = af.SimulationFileHeader(mesh.num_vertices, STEPS_PER_FRAME * h, h)
    frames_written = 0
    with af.SimulationWriter(path, header) as writer:
        with pytest.raises(af.NumericalError) as error:
            for frame in range(20):
                stepper.step(STEPS_PER_FRAME)
                writer.append_frame(stepper.time, stepper.displacement)
                frames_written += 1
        before = (stepper.time, stepper.displacement.copy())
    message = str(error.value)
    # The time of the failing step (the one after the state kept), the vertex and coordinate.
    step_time = before[0] + h
    match = re.search(r"non-finite internal force \(nan\) in the step to time ([0-9.]+) at DOF (\d+) "
                      r"\(vertex (\d+), coordinate y\)", message)
    assert match, message
    assert float(match.group(1)) == pytest.approx(step_time, abs=1e-6)  # printed with 6 decimals
    assert int(match.group(2)) == 3 * BAD_VERTEX + 1 and int(match.group(3)) == BAD_VERTEX
    assert "the state was left at the start of the step" in message
    assert np.isfinite(before[1]).all()
    assert frames_written >= 1  # the fault came after some frames

    reader = af.SimulationReader(path)
    reader.verify_all()
    assert len(reader) == frames_written
    for k in range(len(reader)):
        assert np.isfinite(reader.read_frame(k).displacement).all()


def test_the_writer_refuses_a_nan_frame(tmp_path):
    """Second line of defence: a NaN a user loop passes on anyway never reaches the file."""
    mesh = small_box()
    path = tmp_path / "refused.afsim"
    header = af.SimulationFileHeader(mesh.num_vertices, 0.05, 0.01)
    u = np.zeros(mesh.num_dofs)
    with af.SimulationWriter(path, header) as writer:
        writer.append_frame(0.05, u)
        u[3 * BAD_VERTEX] = np.nan
        with pytest.raises(af.Error):
            writer.append_frame(0.1, u)
    reader = af.SimulationReader(path)
    assert len(reader) == 1 and np.isfinite(reader.read_frame(0).displacement).all()


def test_run_monitor_names_the_frame():
    """The library's frame loop from Python (af.RunMonitor, as offlineSimulator runs it): the
    same NaN, stepped frame by frame, names the frame, step and vertex, in the message and as
    fields of the exception; the state stays at the start of the failing step."""
    mesh = small_box(cells=4)
    problem = af.Problem(mesh, mesh.set_vertices("xmin"))
    system = problem.dynamic_system()
    pull = np.zeros(mesh.num_dofs)
    pull.reshape(-1, 3)[mesh.set_vertices("xmax")] = [0.0, -5.0, 0.0]
    system.external_force = lambda t, u, v: pull
    system.force_model = NaNAfterSomeCalls(problem.stiffness_matrix())
    h = 0.01
    options = af.IntegratorOptions()
    options.max_iterations = 3
    stepper = af.BackwardEuler(system, h, options)
    # The pull is set on the system, not given to the problem as a load, so the monitor's
    # energy check (which knows the problem's loads only) is off.
    monitor = af.RunMonitor(problem, energy_check=False)
    finished = -1
    with pytest.raises(af.NumericalError) as error:
        for frame in range(20):
            monitor.advance_frame(stepper, frame, STEPS_PER_FRAME)
            finished = frame
    fault = error.value
    assert fault.frame == finished + 1 >= 1  # the frame after the last finished one
    assert fault.step == int(round(stepper.time / h)) + 1  # 1-based: the step after the state kept
    assert fault.vertex == BAD_VERTEX and fault.dof == 3 * BAD_VERTEX + 1
    assert fault.time == pytest.approx(stepper.time + h, abs=1e-12)
    assert str(fault).startswith(f"frame {fault.frame} (step {fault.step}, t = ")
    assert np.isfinite(stepper.displacement).all()
    with pytest.raises(ValueError, match="steps_per_frame"):
        monitor.advance_frame(stepper, 0, 0)
