# SPDX-License-Identifier: BSD-3-Clause
"""Penalty contact from Python: the force against a plane and a sphere, the potential it
comes from, and a Problem's loads carrying it (last_change against last_window_change)."""
import numpy as np
import pytest

import asyncfem as af


def plane_contact(stiffness=100.0):
    rest = np.array([[0.0, 0.5, 0.0], [1.0, 0.5, 0.0]])
    parameters = af.PenaltyContactParameters()
    parameters.stiffness = stiffness
    return af.PenaltyContact(rest, planes=[af.ContactPlane([0.0, 1.0, 0.0], 0.0)], parameters=parameters)


def test_a_plane_pushes_a_penetrating_vertex_by_k_times_its_depth():
    contact = plane_contact()
    u = np.zeros(6)
    u[1] = -0.52  # vertex 0 ends 0.02 below the ground; vertex 1 stays 0.5 above it
    zero = np.zeros(6)
    # d = 0 - (0.5 - 0.52): a few ulps of 0.5 off, 1e-12 relative to d = 0.02 is far above that.
    force = contact.forces(u, zero)
    assert force[1] == pytest.approx(100.0 * 0.02, rel=1e-12)
    assert np.count_nonzero(force) == 1
    assert contact.max_penetration(u) == pytest.approx(0.02, rel=1e-12)
    assert contact.active_contacts(u) == 1
    assert contact.energy(u) == pytest.approx(0.5 * 100.0 * 0.02**2, rel=1e-12)
    assert list(contact.vertices_within(u)) == [0]
    assert list(contact.vertices_within(u, 0.6)) == [0, 1]
    assert not contact.forces(u, zero, vertices=[1]).any()  # only vertex 1 tested
    assert contact.parameters.stiffness == 100.0
    # Moving away from the plane: damping c = 0, so the force is still k d (it never pulls).
    moving = zero.copy()
    moving[1] = 3.0
    assert contact.forces(u, moving)[1] == pytest.approx(2.0, rel=1e-12)


def test_sphere_forces_are_minus_the_gradient_of_the_energy():
    rest = np.array([[0.1, 0.2, 0.0], [2.0, 0.0, 0.0], [-0.3, 0.1, 0.25]])
    parameters = af.PenaltyContactParameters()
    parameters.stiffness = 50.0
    contact = af.PenaltyContact(rest, spheres=[af.ContactSphere([0.0, 0.0, 0.0], 0.5)], parameters=parameters)
    u = np.array([0.02, -0.01, 0.03, 0.0, 0.0, 0.0, 0.01, 0.02, -0.02])
    force = contact.forces(u, np.zeros(9))
    assert contact.active_contacts(u) == 2
    # Central differences with step 1e-6: the truncation error h^2 |E'''| / 6 (E''' ~ k / r^2
    # ~ 200 here) and the round-off 1e-16 |E| / h (E ~ 1) are both below 1e-9, so 1e-7
    # absolute on forces of order k d ~ 10.
    step = 1e-6
    gradient = np.zeros(9)
    for i in range(9):
        e = np.zeros(9)
        e[i] = step
        gradient[i] = (contact.energy(u + e) - contact.energy(u - e)) / (2 * step)
    np.testing.assert_allclose(force, -gradient, rtol=0, atol=1e-7)
    assert np.abs(force).max() > 1.0  # a real contact, not two zeros


def test_bad_obstacles_and_shapes_are_refused():
    rest = np.zeros((2, 3))
    with pytest.raises(af.ValidationError, match="radius"):
        af.PenaltyContact(rest, spheres=[af.ContactSphere([0.0, 0.0, 0.0], -1.0)])
    with pytest.raises(ValueError, match="rest_positions"):
        af.PenaltyContact(np.zeros((2, 2)))


def test_a_problem_carries_its_contact_and_its_last_window_change():
    spec = af.BeamSpec()
    spec.cells_along_length = 4
    beam = af.make_beam_mesh(spec)
    pull = af.VertexLoad(beam.vertex_set("tip"), [0.0, -1.0, 0.0], start=0.0, end=0.3)
    contact = af.PenaltyContact(beam.rest_positions, planes=[af.ContactPlane([0.0, 1.0, 0.0], -0.5)])
    problem = af.Problem(beam, beam.vertex_set("root"), af.ProblemSettings(), [pull], contact=contact)
    assert problem.contact is not None and problem.contact.parameters.stiffness == contact.parameters.stiffness
    # Contact depends on the state, so the loads may change at any time; the windows stop at 0.3.
    assert problem.last_change() == float("inf")
    assert problem.last_window_change() == pytest.approx(0.3)
    plain = af.Problem(beam, beam.vertex_set("root"))
    assert plain.contact is None
    assert plain.last_window_change() == 0.0
