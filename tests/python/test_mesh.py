# SPDX-License-Identifier: BSD-3-Clause
"""libraries/volumetricMesh from Python: construction, views, sets, materials, readers,
writers, generators and queries."""
import os

import numpy as np
import pytest

import asyncfem as af
from conftest import BEAM, small_box

UNIT_TET = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])


def test_construct_and_views():
    mesh = af.TetMesh(UNIT_TET, np.array([[0, 1, 2, 3]]), [af.Material("steel", 7800.0, 2e11, 0.3)], [0])
    assert (mesh.num_vertices, mesh.num_elements, mesh.num_dofs) == (4, 1, 12)
    positions = mesh.rest_positions
    assert positions.shape == (4, 3) and not positions.flags.writeable
    np.testing.assert_array_equal(positions, UNIT_TET)  # exact: a view of the stored doubles
    assert mesh.elements.dtype == np.int32 and mesh.elements.tolist() == [[0, 1, 2, 3]]
    assert mesh.materials[0] == af.Material("steel", 7800.0, 2e11, 0.3)
    assert af.signed_element_volume(mesh, 0) == pytest.approx(1.0 / 6.0, rel=1e-15)
    assert af.total_mass(mesh) == pytest.approx(7800.0 / 6.0, rel=1e-15)
    del mesh
    assert positions[1, 0] == 1.0  # the view keeps the mesh alive


def test_sets_and_materials(beam_mesh):
    mesh = af.read_mesh(BEAM)
    assert set(mesh.element_sets) == {"body", "tip"}
    tip = mesh.set_vertices("tip")
    assert len(tip) > 0 and np.all(np.diff(tip) > 0)
    mesh.set_vertex_set("corner", [5, 1, 1])
    assert mesh.vertex_set("corner").tolist() == [1, 5]
    mesh.set_element_set("first", np.array([0, 1]))
    index = mesh.add_material(af.Material("soft", 900.0, 1e5, 0.4))
    mesh.assign_material("first", index)
    assert mesh.element_material(0).name == "soft" and mesh.element_materials[1] == index
    assert mesh.find_material("soft") == index and mesh.find_material("none") == -1
    np.testing.assert_array_equal(mesh.element(0), mesh.elements[0])
    np.testing.assert_array_equal(mesh.element_rest_positions(0).T, mesh.rest_positions[mesh.elements[0]])


def test_readers_and_writers_round_trip(tmp_path, beam_mesh):
    veg = tmp_path / "beam.veg"
    af.write_veg(veg, beam_mesh)
    again, report = af.read_veg(veg, with_report=True)
    assert report.format == "veg"
    np.testing.assert_array_equal(again.rest_positions, beam_mesh.rest_positions)  # writeVeg is exact
    np.testing.assert_array_equal(again.elements, beam_mesh.elements)
    assert again.materials == beam_mesh.materials

    # TetGen and Gmsh: written here by hand from the beam's arrays.
    p, e = beam_mesh.rest_positions, beam_mesh.elements
    with open(tmp_path / "beam.node", "w") as out:
        out.write(f"{len(p)} 3 0 0\n")
        for i, x in enumerate(p):
            out.write(f"{i} {x[0]!r} {x[1]!r} {x[2]!r}\n")
    with open(tmp_path / "beam.ele", "w") as out:
        out.write(f"{len(e)} 4 0\n")
        for i, t in enumerate(e):
            out.write(f"{i} {t[0]} {t[1]} {t[2]} {t[3]}\n")
    tetgen = af.read_tetgen(tmp_path / "beam")
    np.testing.assert_array_equal(tetgen.elements, e)
    with open(tmp_path / "beam.msh", "w") as out:
        out.write("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n")
        out.write(f"{len(p)}\n")
        for i, x in enumerate(p):
            out.write(f"{i + 1} {x[0]!r} {x[1]!r} {x[2]!r}\n")
        out.write(f"$EndNodes\n$Elements\n{len(e)}\n")
        for i, t in enumerate(e):
            out.write(f"{i + 1} 4 2 1 1 {t[0] + 1} {t[1] + 1} {t[2] + 1} {t[3] + 1}\n")
        out.write("$EndElements\n")
    options = af.MeshReadOptions(default_material=af.Material("gel", 1100.0, 5e4, 0.45))
    gmsh, report = af.read_mesh(tmp_path / "beam.msh", options, with_report=True)
    assert report.format == "gmsh 2.2" and gmsh.materials[0].name == "gel"
    np.testing.assert_array_equal(gmsh.rest_positions, p)
    (tmp_path / "fixed.bou").write_text("3, 1\n2\n")
    assert af.read_bou(tmp_path / "fixed.bou", beam_mesh.num_vertices).tolist() == [0, 1, 2]

    u = np.linspace(0.0, 1.0, beam_mesh.num_dofs)
    af.write_vtu(tmp_path / "beam.vtu", beam_mesh, u, point_arrays={"speed": np.ones(beam_mesh.num_vertices)},
                 cell_arrays={"volume": af.element_volumes(beam_mesh)}, encoding=af.VtuEncoding.ascii)
    text = (tmp_path / "beam.vtu").read_text()
    assert 'Name="displacement"' in text and 'Name="speed"' in text and 'Name="volume"' in text
    with pytest.raises(ValueError, match=r"point_arrays\[bad\]"):
        af.write_vtu(tmp_path / "bad.vtu", beam_mesh, point_arrays={"bad": np.ones(3)})
    series = af.VtuSeriesWriter(tmp_path / "series")
    series.write_frame(0, 0.0, beam_mesh, u)
    series.write_frame(1, 0.5, beam_mesh, 2 * u)
    assert (tmp_path / "series" / af.VtuSeriesWriter.frame_file_name(1)).exists()
    assert 'timestep="0.5"' in series.collection_path.read_text()
    af.write_pvd(tmp_path / "all.pvd", [(0.0, "series/frame_00000.vtu")])
    assert "frame_00000.vtu" in (tmp_path / "all.pvd").read_text()


def test_generators():
    box = small_box(cells=2)
    assert box.num_elements == 2 * 6 and {"xmin", "xmax"} <= set(box.vertex_sets)
    beam_spec = af.BeamSpec()
    beam_spec.cells_along_length = 10
    beam = af.make_beam_mesh(beam_spec)
    assert {"root", "tip"} <= set(beam.vertex_sets) and beam.find_material("tip") >= 0
    spec = af.CellMeshSpec()
    spec.cell_size = 0.1
    spec.blocks = [af.CellBlock("base", [0, 0, 0], [2, 1, 2], af.Material("base")),
                   af.CellBlock("post", [0, 1, 0], [1, 3, 1], af.Material("post", 500.0, 1e5, 0.3))]
    spec.vertex_rings = [af.CellVertexRing("postRing", ["post"], 1)]
    cells = af.make_cell_mesh(spec)
    assert cells.num_elements == 6 * (4 + 2) and "postRing" in cells.vertex_sets
    assert "rodAndRing" in af.make_antenna_mesh().vertex_sets
    assert "tentacleTips" in af.make_snail_mesh().vertex_sets


def test_queries(beam_mesh):
    volumes = af.element_volumes(beam_mesh)
    assert volumes.shape == (beam_mesh.num_elements,)
    assert af.total_volume(beam_mesh) == pytest.approx(volumes.sum(), rel=1e-12)  # summation order only
    triangles = af.boundary_triangles(beam_mesh)
    assert triangles.shape[1] == 3 and triangles.dtype == np.int32
    offsets, elements = af.vertex_element_adjacency(beam_mesh)
    assert offsets[-1] == 4 * beam_mesh.num_elements and len(elements) == offsets[-1]
    box = af.bounding_box(beam_mesh)
    np.testing.assert_array_equal(box.min, beam_mesh.rest_positions.min(axis=0))
    moved = af.bounding_box(beam_mesh, np.ones(beam_mesh.num_dofs))
    np.testing.assert_array_equal(moved.max, box.max + 1.0)
    qualities = af.element_qualities(beam_mesh)
    assert qualities["aspect_ratio"].min() >= 1.0 - 1e-12
    assert af.element_quality(beam_mesh, 0).aspect_ratio == qualities["aspect_ratio"][0]
    assert len(af.unused_vertices(beam_mesh)) == 0


def test_hexahedral_mesh_from_arrays():
    """(m, 8) rows make a hexahedral mesh in Vega's CUBIC order; it equals the same cubes read from .veg."""
    read = af.read_mesh(os.path.join(os.path.dirname(__file__), "..", "data", "volumetricMesh", "cubes.veg"))
    mesh = af.TetMesh(read.rest_positions, read.hexahedra, read.materials, read.element_materials)
    assert mesh.element_kind == "hexahedron" and mesh.num_elements == read.num_elements == 4
    np.testing.assert_array_equal(mesh.hexahedra, read.hexahedra)  # exact: the same ids, no reordering
    cube_volume = 0.5**3  # cubes.veg: four cubes of side 0.5
    density = sum(read.materials[m].density for m in read.element_materials)
    assert af.total_mass(mesh) == af.total_mass(read) == pytest.approx(density * cube_volume, rel=1e-14)
    # One unit cube: the volume is 1 (the rows keep their order, so a reversed cube would give -1).
    corners = np.array([[x, y, z] for z in (0.0, 1.0) for y in (0.0, 1.0) for x in (0.0, 1.0)])
    cube = af.TetMesh(corners, np.array([[0, 1, 3, 2, 4, 5, 7, 6]]))
    assert cube.element_kind == "hexahedron"
    assert af.total_mass(cube) == pytest.approx(af.Material().density, rel=1e-14)
    with pytest.raises(ValueError, match=r"\(m, 4\) \(tetrahedra\) or \(m, 8\) \(hexahedra\), got 6"):
        af.TetMesh(corners, np.array([[0, 1, 3, 2, 4, 5]]))
