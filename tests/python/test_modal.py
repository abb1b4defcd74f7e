# SPDX-License-Identifier: BSD-3-Clause
"""Modal analysis and region proposal from Python: lowest_modes, region_modes (the per-mode
S-share report) and propose_scene_regions (what proposeRegions --json reports)."""
import json
import os
import subprocess

import numpy as np
import pytest
import scipy.linalg

import asyncfem as af
from conftest import BINARY_DIR, SOURCE_DIR, small_box

BEAM_SCENE = SOURCE_DIR / "models" / "beam" / "beam.json"


@pytest.fixture(scope="module")
def box_modes():
    mesh = small_box(cells=4)
    free = af.FreeDofs.from_fixed_vertices(mesh.num_vertices, mesh.set_vertices("xmin"))
    stiffness, mass = af.vibration_matrices(mesh, af.MassType.consistent)
    return mesh, free, stiffness, mass, af.lowest_modes(stiffness, mass, free, count=6)


def test_lowest_modes_agree_with_a_dense_eigensolver(box_modes):
    mesh, free, stiffness, mass, result = box_modes
    kept = free.free_to_full
    dense = scipy.linalg.eigh(stiffness.toarray()[np.ix_(kept, kept)], mass.toarray()[np.ix_(kept, kept)],
                              eigvals_only=True, subset_by_index=[0, 5])
    # Lanczos converges the Ritz values to 1e-10 relative (ModalOptions.tolerance); 1e-8
    # leaves room for the dense solver's own rounding on this 60-DOF problem.
    np.testing.assert_allclose(result.eigenvalues, dense, rtol=1e-8)
    np.testing.assert_allclose(result.frequencies, np.sqrt(dense), rtol=1e-8)
    np.testing.assert_allclose(result.hertz, result.frequencies / (2 * np.pi), rtol=1e-15)
    assert result.modes.shape == (mesh.num_dofs, 6)
    assert np.all(result.modes[~np.isin(np.arange(mesh.num_dofs), kept)] == 0.0)  # fixed DOFs are zero
    # M-orthonormal and K phi = lambda M phi, to round-off of the solves (1e-8 of the scale).
    gram = result.modes.T @ (mass @ result.modes)
    np.testing.assert_allclose(gram, np.eye(6), atol=1e-8)
    residual = stiffness @ result.modes - (mass @ result.modes) * result.eigenvalues
    assert np.abs(residual[kept]).max() <= 1e-8 * np.abs(stiffness @ result.modes).max()
    assert result.operator_applications > 0 and result.solve_seconds >= result.factor_seconds >= 0.0


def test_region_shares_add_up_and_the_whole_body_holds_all(box_modes):
    mesh, free, _, mass, result = box_modes
    x = mesh.rest_positions[:, 0]  # cells of 0.075 along x: no element touches both regions below
    left = [v for v in range(mesh.num_vertices) if 0.0 < x[v] < 0.1]
    right = [v for v in range(mesh.num_vertices) if x[v] > 0.2]
    regions = [af.AsyncRegion("left", left, 2), af.AsyncRegion("right", right, 4)]
    report = af.region_modes(result, mass, regions, large_timestep=0.01, frame_rate=30.0)
    assert report.region_names == ["left", "right"] and report.ratios == [2, 4]
    assert len(report.modes) == 6 and report.nyquist_omega == pytest.approx(np.pi * 30.0)
    for mode, omega in zip(report.modes, result.frequencies):
        assert mode.omega == pytest.approx(omega, rel=1e-12)
        assert mode.omega_large_step == pytest.approx(omega * 0.01, rel=1e-12)
        assert mode.omega_substep == pytest.approx([omega * 0.01 / 2, omega * 0.01 / 4], rel=1e-12)
        assert all(0.0 <= share <= 1.0 for share in mode.region_share)
        # The regions share no element, so their shares add up to the union's (round-off),
        # which misses the middle of the box.
        assert sum(mode.region_share) == pytest.approx(mode.fast_share, abs=1e-12)
        assert mode.fast_share < 1.0
    # One region of every free vertex holds the whole modal mass (phi^T M phi = 1, fixed
    # DOFs zero), to the round-off of the M-orthonormalisation.
    everything = [v for v in range(mesh.num_vertices) if x[v] > 0.0]
    whole = af.region_modes(result, mass, [af.AsyncRegion("all", everything, 2)], large_timestep=0.01)
    assert [mode.fast_share for mode in whole.modes] == pytest.approx([1.0] * 6, abs=1e-9)
    assert report.verdict in list(af.ModalVerdict.__members__.values())
    assert report.verdict_text() in report.table() and report.table().startswith("hL = 0.01 s")
    document = report.as_dict()
    assert set(document) == {"regions", "ratios", "modes", "verdict"}
    assert document["modes"][0]["fastShare"] == report.modes[0].fast_share


def test_bad_counts_and_regions_are_errors(box_modes):
    mesh, free, stiffness, mass, result = box_modes
    with pytest.raises(af.ValidationError, match="number of modes must be in"):
        af.lowest_modes(stiffness, mass, free, count=0)
    with pytest.raises(af.ValidationError):
        af.region_modes(result, mass, [af.AsyncRegion("r", [mesh.num_vertices + 5], 2)], large_timestep=0.01)


def test_proposal_reports_its_modal_check_and_cost(box_modes):
    mesh, free, stiffness, mass, _ = box_modes
    options = af.RegionProposalOptions()
    options.large_timestep, options.modal_check, options.target_omega_h = 0.01, True, 1.0
    options.cost_check = False
    proposal = af.propose_regions(mesh, free, options, stiffness, mass)
    document = proposal.as_dict()
    assert set(document) == {"largeTimestep", "target", "largeRegionOmegaH", "regions", "withdrawnRegions",
                             "modalVerdict"}
    assert document["largeTimestep"] == 0.01 and document["target"] == proposal.target_omega_h
    assert [r["name"] for r in document["regions"]] == [r.region.name for r in proposal.regions]
    assert isinstance(proposal.summary(), str) and proposal.summary()
    if proposal.has_modal_report:
        assert proposal.modal_report.verdict_text() == document["modalVerdict"]
    else:
        assert proposal.modal_report is None and document["modalVerdict"] == ""
    assert proposal.cost.evaluated is False  # cost_check off


def assert_same_document(ours, theirs, path="$"):
    """Equal keys, strings, integers and flags; floats to 1e-9 relative (the same
    computation, printed round-trip by the utility)."""
    if isinstance(theirs, dict):
        assert set(ours) == set(theirs), path
        for key in theirs:
            assert_same_document(ours[key], theirs[key], f"{path}.{key}")
    elif isinstance(theirs, list):
        assert len(ours) == len(theirs), path
        for index, (a, b) in enumerate(zip(ours, theirs)):
            assert_same_document(a, b, f"{path}[{index}]")
    elif isinstance(theirs, float):
        assert ours == pytest.approx(theirs, rel=1e-9, abs=1e-12), path
    else:
        assert ours == theirs, path


def test_scene_proposal_is_what_propose_regions_json_prints():
    utility = BINARY_DIR / "bin" / "proposeRegions"
    if not utility.exists():
        pytest.skip("proposeRegions not built (ASYNCFEM_BUILD_UTILITIES=OFF)")
    printed = subprocess.run([str(utility), str(BEAM_SCENE), "--json", "--modes", "6"], check=True,
                             capture_output=True, text=True, env=dict(os.environ, OMP_WAIT_POLICY="passive"))
    theirs = json.loads(printed.stdout)
    ours = af.propose_scene_regions(BEAM_SCENE, modes=6)
    assert_same_document(ours, theirs)
    # The beam's stiff tip is proposed and withdrawn: no visible mode lives in it.
    assert ours["regions"] == [] and [r["name"] for r in ours["withdrawnRegions"]] == ["auto1"]
    assert ours["modes"]["regions"] == ["tip"] and len(ours["modes"]["modes"]) == 6
    assert "modes" not in af.propose_scene_regions(BEAM_SCENE)
