# SPDX-License-Identifier: BSD-3-Clause
"""The bindings the other files do not reach: spec fields, options, statistics, reports."""
import numpy as np
import pytest

import asyncfem as af
from conftest import downward_pull, linear_system, small_box


def test_spec_fields_reach_the_generators():
    region = af.BoxRegion("hard", [1.5, 0.0, 0.0], [2.0, 1.0, 1.0], af.Material("hard", 2000.0, 1e7, 0.3))
    box = af.BoxMeshSpec()
    box.origin, box.material, box.regions = [1.0, 0.0, 0.0], af.Material("soft", 900.0, 1e5, 0.4), [region]
    mesh = af.make_box_mesh(box)
    assert mesh.rest_positions[:, 0].min() == 1.0
    assert {m.name for m in mesh.materials} == {"soft", "hard"} and len(mesh.element_set("hard")) > 0
    beam = af.BeamSpec()
    beam.length, beam.depth, beam.tip_fraction, beam.cells_along_length = 2.0, 0.1, 0.5, 10
    mesh = af.make_beam_mesh(beam)
    assert mesh.rest_positions[:, 0].max() == pytest.approx(2.0) and mesh.rest_positions[:, 2].max() == pytest.approx(0.1)
    assert len(mesh.element_set("tip")) == mesh.num_elements // 2
    cells = af.CellMeshSpec()
    cells.origin = [0.0, 1.0, 0.0]
    cells.blocks = [af.CellBlock("a", [0, 0, 0], [1, 1, 1], af.Material("a"))]
    cells.blocks[0].begin = [0, 0, 0]
    ring = af.CellVertexRing("r", ["a"], 1)
    ring.around, ring.rings = ["a"], 0
    cells.vertex_rings = [ring]
    mesh = af.make_cell_mesh(cells)
    assert mesh.rest_positions[:, 1].min() == 1.0 and len(mesh.vertex_set("r")) == 8
    antenna = af.AntennaSpec()
    antenna.block_cells, antenna.rod_cells, antenna.rod = [4, 2, 4], 3, af.Material("rod", 50.0, 1e5, 0.3)
    assert af.make_antenna_mesh(antenna).element_material(af.make_antenna_mesh(antenna).element_set("rod")[0]).density == 50.0
    snail = af.SnailSpec()
    snail.tentacle_cells, snail.shell, snail.tentacles = 2, af.Material("shell"), af.Material("tentacles", poisson_ratio=0.3)
    mesh = af.make_snail_mesh(snail)
    assert mesh.element_material(mesh.element_set("tentacles")[0]).poisson_ratio == 0.3
    assert "Material(name='shell'" in repr(mesh.element_material(mesh.element_set("shell")[0]))


def test_mesh_edits_and_read_options(tmp_path):
    mesh = small_box()
    first = mesh.element(0)
    mesh.set_element(0, [first[1], first[0], first[2], first[3]])
    assert af.signed_element_volume(mesh, 0) < 0  # swapping two vertices flips the orientation
    path = tmp_path / "flipped.veg"
    af.write_veg(path, mesh)
    with pytest.raises(af.Error):  # writeVeg's round trip holds for positively oriented meshes only
        af.read_veg(path, af.MeshReadOptions(reorient_inverted_elements=False))
    fixed, report = af.read_veg(path, af.MeshReadOptions(degenerate_volume_tolerance=1e-10), with_report=True)
    assert isinstance(report, af.MeshReadReport) and report.reoriented_elements == 1 and report.warnings is not None
    assert report.ignored_elements == 0 and af.signed_element_volume(fixed, 0) > 0
    quality = af.element_quality(fixed, 0)
    assert isinstance(quality, af.ElementQuality) and 0 < quality.min_dihedral_angle < quality.max_dihedral_angle < np.pi
    box = af.BoundingBox([0, 0, 0], [1, 2, 3])
    assert box.max[2] == 3.0
    mesh = small_box()
    with open(tmp_path / "box.msh", "w") as out:  # Gmsh 2.2 with a physical group name
        p, e = mesh.rest_positions, mesh.elements
        out.write('$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n1\n3 7 "inside"\n$EndPhysicalNames\n')
        out.write(f"$Nodes\n{len(p)}\n" + "".join(f"{i + 1} {x[0]!r} {x[1]!r} {x[2]!r}\n" for i, x in enumerate(p)))
        out.write(f"$EndNodes\n$Elements\n{len(e)}\n")
        out.write("".join(f"{i + 1} 4 2 7 1 {t[0] + 1} {t[1] + 1} {t[2] + 1} {t[3] + 1}\n" for i, t in enumerate(e)))
        out.write("$EndElements\n")
    gmsh = af.read_gmsh(tmp_path / "box.msh")
    assert len(gmsh.element_set("inside")) == mesh.num_elements


def test_series_writer_resume(tmp_path):
    mesh = small_box()
    series = af.VtuSeriesWriter(tmp_path / "frames", af.VtuEncoding.binary)
    series.add_existing_frame(0, 0.0)
    series.write_collection()
    assert series.folder == tmp_path / "frames"
    assert "frame_00000.vtu" in series.collection_path.read_text()


def test_options_stats_and_system_fields():
    mesh = small_box()
    system, stiffness, mass = linear_system(mesh, external_force=downward_pull(mesh, "xmax"))
    system.validate()
    system.rayleigh_mass = -1.0
    with pytest.raises(af.ValidationError):
        system.validate()
    system.rayleigh_mass = 0.0
    assert system.mass.shape == stiffness.shape and system.free_dofs.num_free < mesh.num_dofs
    assert system.num_dofs == mesh.num_dofs and system.rayleigh_stiffness == 0.0
    assert isinstance(system.force_model, af.LinearForceModel)
    integrator = af.BackwardEuler(system, 0.01)
    assert isinstance(integrator, af.Integrator) and integrator.stable_timestep_estimate() == float("inf")
    integrator.step(2)
    stats = integrator.stats
    assert isinstance(stats, af.IntegratorStats) and stats.solve_flops > 0 and stats.factor_flops > 0
    assert stats.force_seconds >= 0 and stats.assembly_seconds >= 0
    assert any("damping" in line for line in stats.skipped)  # undamped: the damping products are skipped
    integrator.set_timestep(0.02)
    assert integrator.timestep == 0.02
    reduced_k, reduced_m = system.free_dofs.free_matrix(stiffness), system.free_dofs.free_matrix(mass)
    omega = af.estimate_max_frequency(reduced_k, reduced_m)
    assert 0 < omega <= 1.05 * af.estimate_max_frequency(mesh, af.MassType.consistent)  # estimate vs bound (+10% margin)
    options = af.IntegratorOptions()
    options.max_iterations, options.tolerance = 3, 1e-6
    assert (options.max_iterations, options.tolerance) == (3, 1e-6)

    solver = af.SparseSolver(af.SolverKind.eigen_lu)
    solver.analyze_pattern(reduced_m)
    solver.factorize(reduced_m)
    assert solver.ordering != "none"
    stats = solver.stats
    assert isinstance(stats, af.SolverStats) and stats.analyses == 1 and stats.factor_flops > 0
    assert stats.solve_flops_per_rhs > 0 and stats.analyze_seconds >= 0 and stats.factor_seconds >= 0
    assert af.MatrixAssembler(mesh).elements_per_chunk >= 1


def pull_against_springs(mesh, vertex_set, stiffness):
    """The set pulled down (downward_pull) and held back by springs to its rest position:
    f(u) = pull - stiffness * u on the set's DOFs, a load that depends on the state, so that
    the fast region's predicted substep states (substep_state_prediction) change it."""
    pull = downward_pull(mesh, vertex_set)
    dofs = (3 * np.asarray(mesh.set_vertices(vertex_set))[:, None] + np.arange(3)).ravel()

    def force(time, u, v):
        f = pull(time, u, v).copy()
        f[dofs] -= stiffness * u[dofs]
        return f
    return force


@pytest.mark.parametrize("schur", [af.SchurMode.symmetric, af.SchurMode.lu])
def test_async_options(schur):
    spec = af.BeamSpec()
    spec.cells_along_length = 6
    beam = af.make_beam_mesh(spec)
    system, _, _ = linear_system(beam, fixed_set="root", external_force=pull_against_springs(beam, "tip", 1e3))
    tip = af.region_vertices(beam, element_sets=["tip"])
    region = af.AsyncRegion("tip", [0], 2)
    region.vertices = tip

    def run(method, recovery, prediction):
        options = af.AsyncOptions(schur=schur)
        options.method, options.recovery, options.region_solver = method, recovery, af.SolverKind.eigen_ldlt
        options.substep_state_prediction = prediction
        integrator = af.AsyncBackwardEuler(beam, system, 0.01, [region], options)
        integrator.step(3)
        assert integrator.options.method == method and integrator.options.substep_state_prediction == prediction
        assert integrator.z_column_seconds >= 0 and len(integrator.partition.large_dofs) > 0
        return integrator.displacement.copy()

    results = [run(method, recovery, True)
               for method, recovery in [(af.AsyncSolveMethod.structured, af.RecoveryMode.substitution),
                                        (af.AsyncSolveMethod.structured, af.RecoveryMode.dense_z),
                                        (af.AsyncSolveMethod.naive, af.RecoveryMode.automatic)]]
    # The stable coupling's H^{LL*} is symmetric, so every method solves the same equations:
    # equal to the round-off of different factorizations (1e-9 of the motion).
    scale = np.abs(results[0]).max()
    for other in results[1:]:
        np.testing.assert_allclose(other, results[0], rtol=0, atol=1e-9 * scale)
    # The springs see the predicted substep state (u_0 + r hS v_0) instead of u_0 once the tip
    # moves (steps 2 and 3): without the prediction the motion differs (by 10% of it at these
    # springs; 0 under a constant load), far above the methods' round-off, so the agreement
    # above is with the option acting.
    without = run(af.AsyncSolveMethod.structured, af.RecoveryMode.substitution, False)
    assert np.abs(without - results[0]).max() > 1e-6 * scale


def test_reader_refresh_and_frame(tmp_path):
    path = tmp_path / "grow.afsim"
    writer = af.SimulationWriter(path, af.SimulationFileHeader(1, 0.5))
    reader = af.SimulationReader(path)
    assert reader.num_frames == 0 and reader.path == path
    writer.append_frame(0.5, np.ones(3))
    reader.refresh()  # sees the frame appended since it opened the file
    frame = reader.read_frame(0)
    assert isinstance(frame, af.SimulationFrame) and frame.velocity.size == 0
    assert writer.path == path


@pytest.mark.skipif(not af.has_render, reason="built without rendering")
def test_render_style_fields():
    style = af.RenderStyle()
    style.surface_color, style.crease_angle_degrees = [1.0, 0.0, 0.0], 10.0
    style.ground_colors = [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]]
    ground = af.GroundPlane()
    ground.shadow = False
    camera = af.Camera()
    camera.vertical_field_of_view_degrees = 45.0
    assert style.crease_angle_degrees == 10.0 and not ground.shadow and camera.vertical_field_of_view_degrees == 45.0
