# SPDX-License-Identifier: BSD-3-Clause
"""Single-rate integrators from Python: every kind, options, state, statistics."""
import numpy as np
import pytest

import asyncfem as af
from conftest import downward_pull, linear_system, small_box


@pytest.fixture(scope="module")
def mesh():
    return small_box()


def test_names():
    assert set(af.integrator_names()) == {"backward-euler", "trapezoidal", "central-differences", "symplectic-euler"}


@pytest.mark.parametrize("cls", [af.BackwardEuler, af.Trapezoidal, af.CentralDifferences, af.SymplecticEuler])
def test_every_integrator_steps(mesh, cls):
    system, _, _ = linear_system(mesh, mass_type=af.MassType.lumped, external_force=downward_pull(mesh, "xmax"))
    omega = af.estimate_max_frequency(mesh, af.MassType.lumped)
    h = 0.5 * af.stable_timestep_from_frequency(omega)
    integrator = cls(system, h, af.IntegratorOptions(max_frequency=omega))
    assert integrator.timestep == h and integrator.time == 0.0
    integrator.step(10)
    assert integrator.stats.steps == 10
    assert integrator.time == pytest.approx(10 * h, rel=1e-14)
    u = integrator.displacement
    assert not u.flags.writeable and np.isfinite(u).all()
    tip = mesh.vertex_set("xmax")
    assert (u.reshape(-1, 3)[tip, 1] < 0).all()  # pulled down
    fixed = mesh.vertex_set("xmin")
    assert (u.reshape(-1, 3)[fixed] == 0).all()
    assert integrator.mechanical_energy() > 0.0


def test_explicit_limit(mesh):
    system, _, _ = linear_system(mesh, mass_type=af.MassType.lumped)
    omega = af.estimate_max_frequency(mesh, af.MassType.lumped)
    with pytest.raises(af.ValidationError):
        af.CentralDifferences(system, 4.0 / omega, af.IntegratorOptions(max_frequency=omega))
    forced = af.CentralDifferences(system, 4.0 / omega, af.IntegratorOptions(max_frequency=omega, force=True))
    assert forced.max_frequency == omega and forced.stable_timestep_estimate() == pytest.approx(2.0 / omega)


def test_state_round_trip_is_exact(mesh):
    """Restoring (u, v, t) and the internal state makes the next steps bit-identical."""
    system, _, _ = linear_system(mesh, external_force=downward_pull(mesh, "xmax"))
    for name in af.integrator_names():
        options = af.IntegratorOptions(max_frequency=af.estimate_max_frequency(mesh, af.MassType.consistent))
        h = 1e-4
        a = af.make_integrator(name, system, h, options)
        a.step(5)
        u, v, t, internal = a.displacement.copy(), a.velocity.copy(), a.time, a.internal_state()
        a.step(5)
        b = af.make_integrator(name, system, h, options)
        b.set_state(u, v, t)
        b.set_internal_state(internal)
        b.step(5)
        np.testing.assert_array_equal(b.displacement, a.displacement)


def test_backward_euler_options_and_stats(mesh):
    system, _, mass = linear_system(mesh, external_force=downward_pull(mesh, "xmax"))
    system.force_model = af.CorotationalLinearFEM(mesh)
    system.rayleigh_mass, system.rayleigh_stiffness = 0.1, 0.001
    options = af.IntegratorOptions(solver=af.SolverKind.eigen_ldlt, max_iterations=5, tolerance=1e-10)
    integrator = af.BackwardEuler(system, 0.01, options)
    integrator.step(3)
    assert integrator.options.solver == af.SolverKind.eigen_ldlt
    assert 1 <= integrator.last_iterations <= 5 and integrator.last_relative_residual >= 0.0
    stats = integrator.stats
    # The default path keeps its factor while that pays (how long is the cost model's
    # choice): at least one factorization, never more than one per solve.
    assert 1 <= stats.factorizations <= stats.solved_right_hand_sides and stats.solved_right_hand_sides >= 3
    assert stats.factorization_seconds >= 0.0
    # The exact path factors once per Newton iteration, so at least once per step.
    exact = af.BackwardEuler(system, 0.01, af.IntegratorOptions(solver=af.SolverKind.eigen_ldlt, max_iterations=5,
                                                                tolerance=1e-10, reuse_factor=False))
    exact.step(3)
    assert exact.stats.factorizations == exact.stats.solved_right_hand_sides >= 3
    integrator.timestep = 0.005
    assert integrator.timestep == 0.005
    trapezoidal = af.Trapezoidal(system, 0.01)
    assert trapezoidal.acceleration.shape == (mesh.num_dofs,)


def test_system_checks(mesh):
    system, stiffness, mass = linear_system(mesh)
    with pytest.raises(ValueError, match="system.force_model: not set"):
        af.BackwardEuler(af.DynamicSystem(None, mass, system.free_dofs), 0.01)
    small = af.FreeDofs.from_fixed_vertices(2, [0])
    with pytest.raises(ValueError, match="system.free_dofs"):
        af.BackwardEuler(af.DynamicSystem(system.force_model, mass, small), 0.01)
    with pytest.raises(ValueError, match="external_force: expected a callable"):
        system.external_force = 3
    system.external_force = lambda t, u, v: np.zeros(2)
    integrator = af.BackwardEuler(system, 0.01)
    with pytest.raises(ValueError, match="external_force return value"):
        integrator.step()
    assert system.external_force is not None
    with pytest.raises(ValueError, match="count"):
        integrator.step(-1)


def test_step_releases_the_gil():
    """While one thread is inside step(n), another thread runs Python code. Had step kept
    the GIL, the other thread could only run just before the call is entered or just after
    it returns (a GIL switch between two bytecodes, within the 5 ms switch interval), never
    in the middle 60% of a call that lasts 50 ms or more."""
    import threading
    import time

    beam = af.make_beam_mesh(af.BeamSpec())
    system, _, _ = linear_system(beam, fixed_set="root", external_force=None)
    integrator = af.BackwardEuler(system, 1e-3)
    integrator.step()

    def run_alongside(steps):
        """Steps `steps` times in a thread while this one records when it runs."""
        window, stamps = {}, []

        def stepper():
            window["start"] = time.perf_counter()
            integrator.step(steps)
            window["end"] = time.perf_counter()

        thread = threading.Thread(target=stepper)
        thread.start()
        while thread.is_alive():
            stamps.append(time.perf_counter())
            time.sleep(0)
        thread.join()
        return window, stamps

    # The call must outlast the GIL switch interval many times over for the test to tell
    # anything: the step count doubles until it does (a precondition, not a speed check).
    steps = 500
    window, stamps = run_alongside(steps)
    while window["end"] - window["start"] <= 0.05 and steps < 500 * 2**10:
        steps *= 2
        window, stamps = run_alongside(steps)
    duration = window["end"] - window["start"]
    middle = (window["start"] + 0.2 * duration, window["end"] - 0.2 * duration)
    inside = [t for t in stamps if middle[0] < t < middle[1]]
    assert len(inside) > 0, f"no Python ran during the middle of {duration:.3f} s of stepping"
