# SPDX-License-Identifier: BSD-3-Clause
"""Force models from Python: linear, corotational (forces against finite differences), and
a force model written in Python driving the integrators."""
import numpy as np
import pytest
import scipy.sparse

import asyncfem as af
from conftest import linear_system, small_box


class PythonLinearModel(af.ForceModel):
    """f_int(u) = K u written in Python: must reproduce LinearForceModel exactly."""

    def __init__(self, stiffness):
        af.ForceModel.__init__(self)
        self.stiffness = stiffness
        self.calls = 0

    def num_dofs(self):
        return self.stiffness.shape[0]

    def is_linear(self):
        return True

    def create_stiffness_matrix(self):
        zero = self.stiffness.copy()
        zero.data[:] = 0.0
        return zero

    def internal_forces(self, u):
        self.calls += 1
        return self.stiffness @ u

    def tangent_stiffness(self, u):
        return self.stiffness

    def elastic_energy(self, u):
        return 0.5 * u @ (self.stiffness @ u)


def test_linear_force_model():
    mesh = small_box()
    _, stiffness, _ = linear_system(mesh)
    model = af.LinearForceModel(stiffness)
    u = np.random.default_rng(0).standard_normal(mesh.num_dofs)
    np.testing.assert_allclose(model.internal_forces(u), stiffness @ u, rtol=1e-12, atol=1e-12 * abs(stiffness).max())
    assert model.is_linear() and model.num_dofs() == mesh.num_dofs
    assert abs(model.tangent_stiffness(u) - stiffness).max() == 0.0
    assert model.elastic_energy(u) == pytest.approx(0.5 * u @ (stiffness @ u), rel=1e-12)
    assert model.element_tangent(u, 0) is None  # built from a matrix: no per-element form


@pytest.mark.parametrize("kind", [af.TangentKind.simple, af.TangentKind.exact])
def test_corotational_forces_and_tangent(kind):
    mesh = small_box()
    assembler = af.MatrixAssembler(mesh)
    model = af.CorotationalLinearFEM(mesh, assembler, kind)
    assert model.tangent_kind == kind and model.num_elements == mesh.num_elements
    rng = np.random.default_rng(2)
    u = 0.01 * rng.standard_normal(mesh.num_dofs)
    forces, tangent = model.forces_and_tangent(u)
    np.testing.assert_array_equal(forces, model.internal_forces(u))
    assert model.rotations.shape == (mesh.num_elements, 3, 3)
    assert np.allclose(np.linalg.det(model.rotations), 1.0, atol=1e-12)
    # Energy gradient = forces: central differences with step 1e-6 (truncation ~1e-12 of
    # the energy's third derivative, round-off ~1e-16 |E| / 1e-6), tolerance 1e-6 relative.
    direction = rng.standard_normal(mesh.num_dofs)
    step = 1e-6
    slope = (model.elastic_energy(u + step * direction) - model.elastic_energy(u - step * direction)) / (2 * step)
    assert slope == pytest.approx(forces @ direction, rel=1e-6)
    # Exact tangent = derivative of the forces, same finite difference, relative 1e-5.
    if kind == af.TangentKind.exact:
        difference = (model.internal_forces(u + step * direction) - model.internal_forces(u - step * direction)) / (2 * step)
        np.testing.assert_allclose(tangent @ direction, difference, rtol=0, atol=1e-5 * np.abs(difference).max())
    element = model.element_tangent(u, 0)
    assert element.shape == (12, 12)
    assert model.element_stiffness(0).shape == (12, 12)
    assert model.assembler.non_zeros == assembler.non_zeros
    model.tangent_kind = af.TangentKind.simple
    assert model.tangent_kind == af.TangentKind.simple


def test_python_force_model_matches_linear():
    """A force model written in Python gives the same steps as the C++ one, bit for bit."""
    mesh = small_box()
    system, stiffness, mass = linear_system(mesh)
    python_model = PythonLinearModel(stiffness)
    pull = np.zeros(mesh.num_dofs)
    pull.reshape(-1, 3)[mesh.vertex_set("xmax")] = [0.0, -1.0, 0.0]
    for name in ["backward-euler", "trapezoidal"]:
        results = []
        for model in [af.LinearForceModel(stiffness), python_model]:
            system = af.DynamicSystem(model, mass, system.free_dofs, external_force=lambda t, u, v: pull)
            integrator = af.make_integrator(name, system, 0.01)
            integrator.step(20)
            results.append(integrator.displacement.copy())
        # K u by SciPy and by Eigen may sum in different orders: equal to round-off.
        np.testing.assert_allclose(results[1], results[0], rtol=0, atol=1e-12 * np.abs(results[0]).max())
    assert python_model.calls > 0


def test_python_force_model_errors():
    mesh = small_box()
    system, stiffness, mass = linear_system(mesh)

    class WrongSize(PythonLinearModel):
        def internal_forces(self, u):
            return np.zeros(3)

    system.force_model = WrongSize(stiffness)
    with pytest.raises(ValueError, match=r"internal_forces\(\) return value: expected a float64 array of shape"):
        af.BackwardEuler(system, 0.01).step()

    class Raises(PythonLinearModel):
        def internal_forces(self, u):
            raise KeyError("from Python")

    system.force_model = Raises(stiffness)
    with pytest.raises(KeyError, match="from Python"):
        af.BackwardEuler(system, 0.01).step()

    class Incomplete(af.ForceModel):
        def num_dofs(self):
            return mesh.num_dofs

    with pytest.raises(TypeError, match="does not implement create_stiffness_matrix"):
        af.BackwardEuler(af.DynamicSystem(Incomplete(), mass, system.free_dofs), 0.01)


def test_python_model_outlives_its_name():
    """The integrator keeps the Python object alive after the last Python reference goes."""
    mesh = small_box()
    system, stiffness, mass = linear_system(mesh)
    system.force_model = PythonLinearModel(stiffness)
    integrator = af.BackwardEuler(system, 0.01)
    del system
    integrator.step(2)
    assert np.isfinite(integrator.displacement).all()
    assert isinstance(scipy.sparse.csc_matrix(stiffness), scipy.sparse.csc_matrix)
