"""The problem layer from Python: loads as objects, matrices on request, integrators on it."""
import math
import os

import numpy as np
import pytest

import asyncfem as af

MODELS = os.environ.get("ASYNCFEM_MODELS_DIR", os.path.join(os.path.dirname(__file__), "..", "..", "models"))


@pytest.fixture
def beam():
    spec = af.BeamSpec()
    spec.cells_along_length = 6
    return af.make_beam_mesh(spec)


def test_problem_builds_nothing_until_asked(beam):
    tip = beam.vertex_set("tip")
    pull = af.VertexLoad(tip, [0.0, -1.0, 0.0], start=0.0, end=0.1)
    problem = af.Problem(beam, beam.vertex_set("root"), af.ProblemSettings(), [pull])
    assert problem.assemblies == 0
    assert problem.breakpoints() == [0.0, 0.1]
    assert problem.last_change() == pytest.approx(0.1)
    f = problem.external_force(0.05).reshape(-1, 3)
    assert (f[tip, 1] == -1.0).all() and np.count_nonzero(f) == len(tip)
    assert not problem.external_force(0.1).any()  # the window excludes its end
    assert problem.assemblies == 0  # loads without gravity need no mass matrix


def test_integrator_on_a_problem_moves_the_tip(beam):
    tip = beam.vertex_set("tip")
    settings = af.ProblemSettings(force_model="corotational", gravity=[0.0, -9.81, 0.0])
    problem = af.Problem(beam, beam.vertex_set("root"), settings)
    integrator = af.BackwardEuler(problem.dynamic_system(), 0.01)
    assert problem.assemblies == 1  # M only (gravity M g reuses it; the corotational model has its own tangent)
    for _ in range(5):
        integrator.step()
    u = np.asarray(integrator.displacement).reshape(-1, 3)
    assert (u[tip, 1] < 0).all()
    assert (u[beam.vertex_set("root")] == 0).all()
    # Gravity M g: the constant load sums to the weight.
    weight = problem.constant_load().reshape(-1, 3)[:, 1].sum()
    mass = problem.mass_matrix().sum() / 3.0
    assert weight == pytest.approx(-9.81 * mass, rel=1e-9)


def test_bad_arguments_are_value_errors(beam):
    with pytest.raises(ValueError, match="per_vertex"):
        af.VertexLoad([0], [1.0, 2.0])
    with pytest.raises(ValueError, match="force_model"):
        af.ProblemSettings(force_model="rubber")
    with pytest.raises(af.ValidationError):
        af.Problem(beam, list(range(beam.num_vertices)))  # every vertex fixed


def test_load_problem_from_a_scene_file():
    problem = af.load_problem(os.path.join(MODELS, "beam", "beam.json"))
    assert problem.assemblies == 0
    assert problem.mesh.num_vertices > 0 and len(problem.fixed_vertices) > 0
    assert len(problem.loads) >= 1 and math.isfinite(problem.last_change())
