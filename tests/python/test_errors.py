# SPDX-License-Identifier: BSD-3-Clause
"""asyncfem::Error and its subclasses arrive as Python exceptions with their fields."""
import pytest

import asyncfem as af
from conftest import small_box


def test_hierarchy():
    assert issubclass(af.Error, RuntimeError)
    for cls in (af.ParseError, af.ValidationError, af.NumericalError):
        assert issubclass(cls, af.Error)


def test_parse_error_fields(tmp_path):
    path = tmp_path / "bad.veg"
    path.write_text("*VERTICES\n2 3 0 0\n1 0 0 0\n2 1.0 0.0 zero\n")
    with pytest.raises(af.ParseError) as info:
        af.read_mesh(path)
    error = info.value
    assert error.file == str(path)
    assert error.line == 4  # the line with the malformed coordinate
    assert str(error).startswith(f"{path}:4:")
    assert error.message == str(error)


def test_validation_error():
    mesh = small_box()
    with pytest.raises(af.ValidationError, match="nosuchset"):
        mesh.vertex_set("nosuchset")


def test_numerical_error():
    # K alone (no mass) with nothing fixed is singular: CHOLMOD reports it.
    mesh = small_box()
    stiffness = af.linear_stiffness_matrix(mesh, af.MatrixAssembler(mesh))
    solver = af.SparseSolver(af.SolverKind.cholmod)
    with pytest.raises(af.NumericalError):
        solver.compute(stiffness)


def test_plain_error():
    with pytest.raises(af.Error, match="cannot read"):
        af.read_mesh("/nonexistent/mesh.veg")
    with pytest.raises(af.Error, match="eigen-ldlt"):
        af.parse_solver_kind("nosuchsolver")
