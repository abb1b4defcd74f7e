// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <asyncfem/asyncIntegrator/regionPartition.hpp>
#include <asyncfem/modalAnalysis/regionModes.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <optional>
#include <vector>

namespace asyncfem {

/// Highest natural frequency (rad/s) of every element on its own: omega_e^2 is the largest
/// eigenvalue of K_e v = lambda M_e v with the element's lumped mass. By the element
/// eigenvalue inequality, max_e omega_e bounds the assembled system's highest frequency
/// from above, so it is a safe measure of how small a timestep an element wants.
Eigen::VectorXd elementMaxFrequencies(const TetMesh& mesh);

struct AutoRegionOptions {
  double largeTimestep = 1e-2;  ///< hL (s)
  /// Target for omega * h in every region: an element with omega_e hL above it wants a
  /// fast region with ratio ceil(omega_e hL / target). <= 0: relative mode (below).
  double targetOmegaH = 0.0;
  /// Relative mode: target = relativeThreshold * median(omega_e) * hL. Implicit integrators
  /// run with omega_max h far above 1 (the highest element modes are invisible and damped
  /// away); what matters is that stiff or light parts are not resolved much worse than the
  /// bulk, so the default marks elements more than 3x "faster" than the median one.
  double relativeThreshold = 3.0;
  /// Rings of vertices added around each fast region (0: none). Growing moves the
  /// interface away from the stiff material and rounds its outline, which keeps the
  /// interface (the dense part of H^{LL*}) small relative to |S|.
  int growLayers = 1;
  int maxRatio = 256;
  /// Modal check (docs/asynchronous-integrator.md, "Which modes can async keep?"), run by
  /// the overload of suggestRegions() that takes K and M: the regions are withdrawn when no
  /// visible mode (omega below pi * frameRate) among the lowest ones has a share of modal
  /// mass >= modalCriteria::minFastShare in them. Async with such regions keeps nothing
  /// that single-rate at hL loses, at m times the cost in S. Off by default here; the scene
  /// path ("regions": "auto") and the suggestRegions utility turn it on.
  bool modalCheck = false;
  double frameRate = 30.0;  ///< frames per second, for the visibility test
  /// Modes computed first; doubled while the highest is still visible, up to maxModalCount.
  int modalCount = 20;
  int maxModalCount = 80;
};

/// One proposed fast region with its statistics.
struct ProposedRegion {
  AsyncRegion region;
  double maxFrequency = 0.0;  ///< max omega_e over its elements (rad/s)
  int numElements = 0;        ///< elements with every vertex in the region
  int numInterfaceDofs = 0;   ///< |I| of the region once partitioned
};

struct AutoRegionProposal {
  std::vector<ProposedRegion> regions;
  double largeRegionMaxFrequency = 0.0;  ///< max omega_e over elements touching no fast vertex
  double largeTimestep = 0.0;
  double targetOmegaH = 0.0;  ///< the target in effect (absolute, or from the relative mode)
  /// Set when the modal check ran (there were regions to check): the report for the regions
  /// the frequency criterion proposed.
  std::optional<RegionModeReport> modalReport;
  /// Regions the frequency criterion proposed and the modal check withdrew (regions is then
  /// empty: the asynchronous integrator runs single-rate at hL).
  std::vector<ProposedRegion> withdrawnRegions;
  double modalSeconds = 0.0;  ///< time of the eigensolves of the modal check
  /// The regions alone, ready for RegionPartition / AsyncBackwardEuler.
  std::vector<AsyncRegion> asyncRegions() const;
};

/// Proposes fast regions so that every region's omega * h stays under the target:
/// elements whose omega_e hL exceeds the target are marked, their vertices grown by
/// growLayers rings, enclosed L vertices (all neighbours fast) filled in, and each
/// connected component becomes one region (so regions never share an element: components
/// that would touch are one component) with ratio = ceil(max omega_e hL / target), capped
/// at maxRatio. Components without free DOFs are dropped. The proposal is a valid
/// partition for RegionPartition.
/// Ignores options.modalCheck (it needs K and M: use the overload below).
AutoRegionProposal suggestRegions(const TetMesh& mesh, const FreeDofs& freeDofs, const AutoRegionOptions& options);

/// The same proposal, followed by the modal check when options.modalCheck is set:
/// lowestModes() of stiffness and mass (full 3n x 3n, e.g. vibrationMatrices()) and
/// analyseRegionModes() of the proposed regions at hL = options.largeTimestep; when its
/// verdict is ModalVerdict::noVisibleModeInFast the regions move to withdrawnRegions.
/// The mode counts are clamped to the free DOFs - 1. Throws ValidationError for frameRate <= 0
/// or counts out of order, and what lowestModes() throws.
AutoRegionProposal suggestRegions(const TetMesh& mesh, const FreeDofs& freeDofs, const AutoRegionOptions& options,
                                  const Eigen::SparseMatrix<double>& stiffness,
                                  const Eigen::SparseMatrix<double>& mass);

/// The regions as the modal report takes them (name, vertices, ratio).
std::vector<ModalRegion> modalRegions(const std::vector<AsyncRegion>& regions);

}  // namespace asyncfem
