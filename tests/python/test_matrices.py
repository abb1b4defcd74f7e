# SPDX-License-Identifier: BSD-3-Clause
"""libraries/stiffnessMatrix and libraries/sparseSolver from Python (SciPy csc matrices)."""
import numpy as np
import pytest
import scipy.sparse

import asyncfem as af
from conftest import small_box


@pytest.fixture(scope="module")
def matrices():
    mesh = small_box()
    assembler = af.MatrixAssembler(mesh)
    return mesh, assembler, af.linear_stiffness_matrix(mesh, assembler), af.mass_matrix(mesh, assembler)


def test_stiffness_and_mass(matrices):
    mesh, assembler, stiffness, mass = matrices
    assert isinstance(stiffness, scipy.sparse.csc_matrix) and stiffness.shape == (mesh.num_dofs,) * 2
    assert stiffness.nnz == assembler.non_zeros and mass.nnz == assembler.non_zeros
    # Rigid translations are in the null space of K (tolerance: round-off of sums of ~1e6 entries).
    translation = np.tile([1.0, 0.0, 0.0], mesh.num_vertices)
    assert np.abs(stiffness @ translation).max() <= 1e-9 * abs(stiffness).max()
    # 1_x^T M 1_x = total mass (relative round-off of the element sums).
    assert translation @ (mass @ translation) == pytest.approx(af.total_mass(mesh), rel=1e-12)
    lumped = af.mass_matrix(mesh, assembler, af.MassType.lumped)
    assert scipy.sparse.triu(lumped, 1).count_nonzero() == 0
    damping = af.rayleigh_damping(mass, stiffness, 0.5, 0.01)
    assert abs(damping - (0.5 * mass + 0.01 * stiffness)).max() <= 1e-12 * abs(stiffness).max()
    combined = af.combine([1.0, 2.0], [mass, stiffness])
    assert abs(combined - (mass + 2.0 * stiffness)).max() == 0.0  # one addition per entry, same order
    assert assembler.create_matrix().nnz == assembler.non_zeros and assembler.num_colors >= 1
    assert 0 <= assembler.slot(0, 0, 0) < assembler.non_zeros


def test_element_matrices():
    positions = np.array([[0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]])
    gradients, volume = af.shape_function_gradients(positions)
    assert volume == pytest.approx(1.0 / 6.0, rel=1e-15)
    np.testing.assert_allclose(gradients.sum(axis=1), 0.0, atol=1e-15)  # partition of unity
    element = af.linear_element_stiffness(positions, 1e6, 0.3)
    assert element.shape == (12, 12) and np.array_equal(element, element.T)
    lam, mu = af.lame_parameters(1e6, 0.25)
    assert lam == pytest.approx(4e5) and mu == pytest.approx(4e5)
    assert af.consistent_element_mass(1.0, 20.0)[0, 0] == pytest.approx(2.0)
    assert af.lumped_element_mass(1.0, 4.0)[0, 0] == pytest.approx(1.0)


def test_free_dofs_and_extraction(matrices):
    mesh, _, stiffness, mass = matrices
    fixed = mesh.vertex_set("xmin")
    free = af.FreeDofs.from_fixed_vertices(mesh.num_vertices, fixed)
    assert free.num_fixed == 3 * len(fixed) and free.is_fixed(3 * fixed[0])
    full = np.arange(mesh.num_dofs, dtype=float)
    np.testing.assert_array_equal(free.restrict(full), full[free.free_to_full])
    assert free.expand(free.restrict(full))[3 * fixed[0]] == 0.0
    reduced = free.free_matrix(stiffness)
    index = free.free_to_full
    assert abs(reduced - stiffness[index][:, index]).max() == 0.0
    extractor = af.SubmatrixExtractor(stiffness, index, index)
    assert abs(extractor.extract(stiffness) - reduced).max() == 0.0
    assert abs(extractor.update(2.0 * stiffness, reduced) - 2.0 * reduced).max() == 0.0
    by_dofs = af.FreeDofs(mesh.num_dofs, [0, 1, 1])
    assert by_dofs.num_fixed == 2 and by_dofs.full_to_free[0] == -1


@pytest.mark.parametrize("kind", ["cholmod", "umfpack", "eigen-ldlt", "eigen-lu", "dense"])
def test_solvers(matrices, kind):
    mesh, _, stiffness, mass = matrices
    free = af.FreeDofs.from_fixed_vertices(mesh.num_vertices, mesh.vertex_set("xmin"))
    system = free.free_matrix(mass + 1e-4 * stiffness)
    solver = af.SparseSolver(kind)
    assert solver.kind == af.parse_solver_kind(kind) and af.solver_kind_name(solver.kind) == kind
    solver.compute(system)
    rhs = np.random.default_rng(1).standard_normal(system.shape[0])
    x = solver.solve(rhs)
    # Residual relative to |A||x|: a backward-stable direct solve on a well-conditioned matrix.
    assert np.linalg.norm(system @ x - rhs) <= 1e-10 * abs(system).max() * np.linalg.norm(x) * system.shape[0]
    block = solver.solve(np.column_stack([rhs, 2 * rhs]))
    assert block.shape == (system.shape[0], 2)
    np.testing.assert_allclose(block[:, 1], 2 * x, rtol=1e-12, atol=1e-12 * np.abs(x).max())
    assert solver.stats.factorizations == 1 and solver.stats.solved_right_hand_sides == 3
    solver.factorize(system)
    assert solver.stats.factorizations == 2
    solver.reset_stats()
    assert solver.stats.factorizations == 0
    with pytest.raises(ValueError, match=r"rhs: expected a float64 array of shape \(36,\)"):
        solver.solve(np.zeros(3))
