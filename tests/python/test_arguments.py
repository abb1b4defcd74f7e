# SPDX-License-Identifier: BSD-3-Clause
"""NumPy arguments of the wrong shape or dtype are ValueErrors that name the argument."""
import numpy as np
import pytest

import asyncfem as af
from conftest import linear_system, small_box


@pytest.fixture(scope="module")
def integrator():
    mesh = small_box()
    system, _, _ = linear_system(mesh)
    return af.BackwardEuler(system, 0.01)


def test_wrong_size_names_argument(integrator):
    n = integrator.num_dofs
    with pytest.raises(ValueError, match=rf"displacement: expected a float64 array of shape \({n},\), got shape \(5,\)"):
        integrator.set_state(np.zeros(5), np.zeros(n))
    with pytest.raises(ValueError, match=r"velocity: .*got shape \(3, 2\)"):
        integrator.set_state(np.zeros(n), np.zeros((3, 2)))


def test_wrong_dtype_names_argument(integrator):
    n = integrator.num_dofs
    with pytest.raises(ValueError, match="displacement: expected dtype float64, got float32"):
        integrator.set_state(np.zeros(n, dtype=np.float32), np.zeros(n))
    with pytest.raises(ValueError, match="velocity: expected dtype float64, got int64"):
        integrator.set_state(np.zeros(n), np.zeros(n, dtype=np.int64))
    with pytest.raises(ValueError, match="displacement: expected an array of numbers"):
        integrator.set_state("abc", np.zeros(n))
    with pytest.raises(ValueError, match="displacement: expected an array, got None"):
        integrator.set_state(None, np.zeros(n))


def test_lists_and_strided_arrays_are_accepted(integrator):
    n = integrator.num_dofs
    strided = np.zeros(2 * n)[::2]  # not contiguous: copied, still accepted
    integrator.set_state([0.0] * n, strided, 0.0)
    assert integrator.time == 0.0


def test_mesh_arrays_checked():
    with pytest.raises(ValueError, match=r"positions: expected a float64 array of shape \(n, 3\), got shape \(4, 2\)"):
        af.TetMesh(np.zeros((4, 2)), np.array([[0, 1, 2, 3]]))
    with pytest.raises(ValueError, match="elements: expected an integer array, got dtype float64"):
        af.TetMesh(np.eye(4, 3), np.array([[0.0, 1.0, 2.0, 3.0]]))
    with pytest.raises(ValueError, match=r"elements: expected an integer array of shape \(n, 4\)"):
        af.TetMesh(np.eye(4, 3), np.array([0, 1, 2, 3]))
    with pytest.raises(ValueError, match="element_materials: expected 1 entries"):
        af.TetMesh(np.eye(4, 3), np.array([[0, 1, 2, 3]]), [af.Material()], [0, 0])


def test_vector_arguments_of_other_bindings():
    mesh = small_box()
    model = af.CorotationalLinearFEM(mesh)
    with pytest.raises(ValueError, match="displacement: expected a float64 array"):
        model.internal_forces(np.zeros(7))
    free = af.FreeDofs.from_fixed_vertices(mesh.num_vertices, [0])
    with pytest.raises(ValueError, match="full: expected"):
        free.restrict(np.zeros(4))
    with pytest.raises(ValueError, match="free: expected"):
        free.expand(np.zeros(mesh.num_dofs))
    with pytest.raises(ValueError, match="fixed_vertices: expected a 1-D list or array of integers"):
        af.FreeDofs.from_fixed_vertices(mesh.num_vertices, np.array([0.5]))


def test_index_checks():
    mesh = small_box()
    with pytest.raises(IndexError, match="element 99999 out of range"):
        mesh.element(99999)
    with pytest.raises(IndexError, match="vertex -1 out of range"):
        mesh.rest_position(-1)
