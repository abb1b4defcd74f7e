# SPDX-License-Identifier: BSD-3-Clause
"""Scene files through the thin scene binding (run_scene, scene_mesh)."""
import numpy as np
import pytest

import asyncfem as af
from conftest import SOURCE_DIR

SCENE = SOURCE_DIR / "models" / "beam" / "beam-single-rate.json"


def test_scene_mesh():
    mesh = af.scene_mesh(SCENE)
    assert mesh.num_vertices == 1519 and mesh.find_material("tip") >= 0


def test_run_scene_writes_what_it_returns(tmp_path):
    output = tmp_path / "beam.afsim"
    frames = af.run_scene(SCENE, output=output, frames=2)
    assert frames.shape == (2, 3 * 1519)
    stored = af.SimulationReader(output).displacements()
    np.testing.assert_array_equal(stored, frames)
    assert frames[1].reshape(-1, 3)[:, 1].min() < 0  # pulled down


def test_run_scene_stores_what_the_scene_output_asks_for(tmp_path):
    """A scene with output.velocities and output.contactForces: the records carry both, and
    a cube released above the ground ends up pushed up by it."""
    scene = tmp_path / "cube.json"
    scene.write_text(
        '{"objects": [{"name": "cube", "translation": [0, 0.002, 0], "mesh": {"generator": "box",'
        ' "size": [0.2, 0.2, 0.2], "cells": [2, 2, 2]}}], "gravity": [0, -9.81, 0],'
        ' "contact": {"ground": {"height": 0}, "stiffness": 2e3, "damping": 20, "implicit": true},'
        ' "output": {"velocities": true, "contactForces": true},'
        ' "integrator": {"name": "backward-euler", "timestep": 0.004166666666666667},'
        ' "frames": {"rate": 30, "count": 4}}')
    output = tmp_path / "cube.afsim"
    frames = af.run_scene(scene, output=output)
    reader = af.SimulationReader(output)
    assert reader.header.has_velocities and reader.header.has_contact_forces
    last = reader.read_frame(3)
    np.testing.assert_array_equal(last.displacement, frames[3])
    assert last.velocity.size == frames.shape[1]
    assert last.contact_force.reshape(-1, 3)[:, 1].sum() > 0  # the ground pushes up


def test_run_scene_errors(tmp_path):
    with pytest.raises(ValueError, match="frames"):
        af.run_scene(SCENE, frames=0)
    bad = tmp_path / "bad.json"
    bad.write_text('{"mesh": {"file": "missing.veg"}}')
    with pytest.raises(af.Error, match="bad.json"):
        af.run_scene(bad)


def test_hexahedral_scene_runs_corotational(tmp_path):
    """Vega's CUBIC mesh through a scene: its kind and hexahedra, and a corotational run."""
    mesh_file = SOURCE_DIR / "tests" / "data" / "volumetricMesh" / "cubes.veg"
    scene = tmp_path / "cubes.json"
    scene.write_text(
        '{"mesh": {"file": "%s"}, "fixed": {"boxes": [{"min": [-0.01, -0.01, -0.01], "max": [0.01, 1.01, 0.51]}]},'
        ' "gravity": [0, 0, -9.81], "forceModel": {"type": "corotational"},'
        ' "integrator": {"name": "backward-euler", "timestep": 0.01}, "frames": {"rate": 50, "count": 2}}' % mesh_file
    )
    mesh = af.scene_mesh(scene)
    assert mesh.element_kind == "hexahedron"
    assert mesh.hexahedra.shape == (mesh.num_elements, 8)
    assert mesh.hexahedra.min() >= 0 and mesh.hexahedra.max() < mesh.num_vertices
    with pytest.raises(af.ValidationError, match="hex-to-tets"):
        mesh.elements
    frames = af.run_scene(scene, frames=2)
    assert frames.shape == (2, mesh.num_dofs) and np.isfinite(frames).all()
    assert frames[1].reshape(-1, 3)[:, 2].min() < 0  # gravity pulls the free end down
