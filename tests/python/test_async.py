# SPDX-License-Identifier: BSD-3-Clause
"""The asynchronous integrator from Python: regions, options, observer, statistics."""
import numpy as np
import pytest

import asyncfem as af
from conftest import downward_pull, linear_system


@pytest.fixture(scope="module")
def beam():
    spec = af.BeamSpec()
    spec.cells_along_length = 8
    return af.make_beam_mesh(spec)


def test_regions_and_partition(beam):
    tip = af.region_vertices(beam, element_sets=["tip"])
    np.testing.assert_array_equal(tip, np.unique(beam.elements[beam.element_set("tip")]))
    assert set(af.region_vertices(beam, vertices=[3, 1], boxes=[([-1, -1, -1], [0.0, 1, 1])])) >= {1, 3}
    free = af.FreeDofs.from_fixed_vertices(beam.num_vertices, beam.vertex_set("root"))
    partition = af.RegionPartition(beam, free, [af.AsyncRegion("tip", tip, 4)])
    assert partition.num_regions == 1 and partition.region(0).ratio == 4
    assert len(partition.region_dofs(0)) == 3 * len(tip)
    assert len(partition.interface_dofs(0)) > 0 and len(partition.interface_elements) > 0
    assert (partition.vertex_region[tip] == 0).all()
    with pytest.raises(af.ValidationError):
        af.RegionPartition(beam, free, [af.AsyncRegion("tip", tip, 0)])


@pytest.mark.parametrize("coupling", [af.AsyncCoupling.stable, af.AsyncCoupling.paper])
def test_async_steps_and_observer(beam, coupling):
    system, _, _ = linear_system(beam, fixed_set="root", external_force=downward_pull(beam, "tip"))
    tip = af.region_vertices(beam, element_sets=["tip"])
    options = af.AsyncOptions(coupling=coupling, schur=af.SchurMode.low_rank)
    integrator = af.AsyncBackwardEuler(beam, system, 0.01, [af.AsyncRegion("tip", tip, 4)], options)
    seen = []
    integrator.set_substep_observer(lambda region, substep, time, u, v: seen.append((region, substep, time, u.size)))
    integrator.step(3)
    assert integrator.name == "async" and integrator.stats.steps == 3
    assert [s[1] for s in seen] == [1, 2, 3, 4] * 3
    assert seen[-1][2] == pytest.approx(0.03, rel=1e-14)
    assert seen[0][3] == len(integrator.partition.region_dofs(0))
    # The stable coupling's H^LL* is symmetric: the default low-rank mode then factors it
    # directly; the paper's coupling keeps the low-rank form.
    expected = af.SchurMode.symmetric if coupling == af.AsyncCoupling.stable else af.SchurMode.low_rank
    assert integrator.schur_mode_used == expected
    assert integrator.factor_non_zeros > 0 and integrator.schur_asymmetry >= 0.0
    assert integrator.solve_floor_seconds(1) > 0.0
    assert (integrator.displacement.reshape(-1, 3)[tip, 1] < 0).all()
    integrator.set_substep_observer(None)
    integrator.step()
    assert len(seen) == 12


def test_async_with_ratio_one_is_backward_euler(beam):
    """m = 1 everywhere: async reduces to backward Euler (same equations); round-off of the
    block solve against one factorization, so compared to 1e-9 of the motion."""
    system, _, _ = linear_system(beam, fixed_set="root", external_force=downward_pull(beam, "tip"))
    tip = af.region_vertices(beam, element_sets=["tip"])
    one = af.AsyncBackwardEuler(beam, system, 0.01, [af.AsyncRegion("tip", tip, 1)])
    reference = af.BackwardEuler(system, 0.01)
    one.step(5)
    reference.step(5)
    scale = np.abs(reference.displacement).max()
    np.testing.assert_allclose(one.displacement, reference.displacement, rtol=0, atol=1e-9 * scale)


def test_z_from_the_regions_modes(beam):
    """AsyncOptions.z_solve: Z from the tip's modes gives the steps Z by substitution gives, to
    round-off (1e-10 of the motion; the two paths round differently)."""
    system, _, _ = linear_system(beam, fixed_set="root", external_force=downward_pull(beam, "tip"))
    tip = af.region_vertices(beam, element_sets=["tip"])
    runs = {}
    for z_solve in (af.ZSolve.substitution, af.ZSolve.modes):
        options = af.AsyncOptions()
        options.z_solve = z_solve
        assert options.z_solve == z_solve
        integrator = af.AsyncBackwardEuler(beam, system, 0.01, [af.AsyncRegion("tip", tip, 16)], options)
        integrator.step(4)
        assert integrator.z_modal_regions == (1 if z_solve == af.ZSolve.modes else 0)
        runs[z_solve] = integrator.displacement
    scale = np.abs(runs[af.ZSolve.substitution]).max()
    assert scale > 0
    np.testing.assert_allclose(runs[af.ZSolve.modes], runs[af.ZSolve.substitution], rtol=0, atol=1e-10 * scale)


def test_proposed_regions(beam):
    """The stiff, light tip of the generated beam is proposed as a fast region (its element
    frequencies are about sqrt(50e6/200 / (1e6/1000)) = 16 times the body's)."""
    free = af.FreeDofs.from_fixed_vertices(beam.num_vertices, beam.vertex_set("root"))
    frequencies = af.element_max_frequencies(beam)
    tip_elements = beam.element_set("tip")
    assert frequencies[tip_elements].min() > 10 * np.delete(frequencies, tip_elements).max()
    options = af.RegionProposalOptions()
    options.large_timestep = 1 / 120
    proposal = af.propose_regions(beam, free, options)
    assert len(proposal.regions) == 1 and not proposal.has_modal_report
    proposed = proposal.regions[0]
    assert set(beam.set_vertices("tip")) <= set(proposed.region.vertices) and proposed.region.ratio > 1
    assert proposed.max_frequency == frequencies[tip_elements].max() and proposed.num_elements >= len(tip_elements)
    assert proposal.large_timestep == options.large_timestep and proposal.target_omega_h > 0
    assert proposal.large_region_max_frequency < proposed.max_frequency
    assert proposal.async_regions()[0].ratio == proposed.region.ratio
    assert proposal.withdrawn_regions == [] and proposal.modal_seconds == 0.0
    for field in ("relative_threshold", "grow_layers", "max_ratio", "frame_rate", "modal_count", "max_modal_count"):
        assert getattr(options, field) > 0
    options.modal_check = True
    assembler = af.MatrixAssembler(beam)
    checked = af.propose_regions(beam, free, options, af.linear_stiffness_matrix(beam, assembler),
                                 af.mass_matrix(beam, assembler))
    assert checked.has_modal_report and checked.modal_seconds > 0
    with pytest.raises(ValueError, match="give both"):
        af.propose_regions(beam, free, options, af.linear_stiffness_matrix(beam, assembler))


def test_touching_regions_run_the_hierarchy_solve(beam):
    """Regions that touch at different ratios run the hierarchy solve by themselves, the
    same vertices as one region the structured Schur solve; at one ratio they are merged."""
    system, _, _ = linear_system(beam, fixed_set="root", external_force=downward_pull(beam, "tip"))
    tip = af.region_vertices(beam, element_sets=["tip"])
    x = beam.rest_positions[:, 0]
    inner = np.array([v for v in tip if x[v] < np.median(x[tip])])
    outer = np.array([v for v in tip if x[v] >= np.median(x[tip])])
    nested = af.AsyncBackwardEuler(beam, system, 0.01, [af.AsyncRegion("inner", inner, 4),
                                                        af.AsyncRegion("outer", outer, 16)])
    assert nested.step_solver == af.AsyncStepSolver.hierarchy
    assert nested.partition.touching
    nested.step(3)
    assert np.abs(nested.displacement).max() > 0.0
    merged = af.AsyncBackwardEuler(beam, system, 0.01, [af.AsyncRegion("inner", inner, 8),
                                                        af.AsyncRegion("outer", outer, 8)])
    assert merged.step_solver == af.AsyncStepSolver.structured_schur
    assert merged.partition.num_regions == 1
    options = af.AsyncOptions()
    options.nested_solve = af.NestedSolve.lu
    with pytest.raises(af.ValidationError, match="nestedSolve"):
        af.AsyncBackwardEuler(beam, system, 0.01, [af.AsyncRegion("tip", tip, 4)], options)


def test_schedule_policy_from_python(beam):
    """A scheduled window opens and closes the fast region at its large-step boundaries."""
    system, _, _ = linear_system(beam, fixed_set="root", external_force=downward_pull(beam, "tip"))
    tip = af.region_vertices(beam, element_sets=["tip"])
    integrator = af.AsyncBackwardEuler(beam, system, 0.01, [])
    options = af.RunTimeRegionOptions()
    options.schedule = [af.ScheduledRegion("tip", tip, 4, start=0.015, end=0.035)]
    integrator.set_run_time_regions(options)
    assert integrator.partition.num_regions == 0
    integrator.step(5)
    records = integrator.repartitions
    assert [r.step for r in records] == [2, 4]
    assert [r.regions for r in records] == [1, 0]
    assert records[0].fast_vertices == len(tip) and records[1].reused
    with pytest.raises(af.ValidationError):
        bad = af.RunTimeRegionOptions()
        bad.contact = True  # this system has no obstacles
        integrator.set_run_time_regions(bad)


def test_indicator_policy_from_python(beam):
    """The indicator policy marks where the large step errs once three velocities are known."""
    system, _, _ = linear_system(beam, fixed_set="root", external_force=downward_pull(beam, "tip"))
    integrator = af.AsyncBackwardEuler(beam, system, 0.01, [])
    options = af.RunTimeRegionOptions()
    options.indicator = True
    options.indicator_tolerance = 0.05
    integrator.set_run_time_regions(options)
    integrator.step(4)
    records = integrator.repartitions
    assert records and records[0].step == 2 and records[0].reason == "indicator region grows"
    assert records[0].fast_vertices > 0
