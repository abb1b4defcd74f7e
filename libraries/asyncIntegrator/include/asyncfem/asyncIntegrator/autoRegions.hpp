// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/asyncIntegrator/regionPartition.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>

#include <Eigen/Core>

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
};

/// One proposed fast region with its statistics.
struct ProposedRegion {
  AsyncRegion region;
  double maxFrequency = 0.0;     ///< max omega_e over its elements (rad/s)
  int numElements = 0;           ///< elements with every vertex in the region
  int numInterfaceDofs = 0;      ///< |I| of the region once partitioned
};

struct AutoRegionProposal {
  std::vector<ProposedRegion> regions;
  double largeRegionMaxFrequency = 0.0;  ///< max omega_e over elements touching no fast vertex
  double largeTimestep = 0.0;
  double targetOmegaH = 0.0;  ///< the target in effect (absolute, or from the relative mode)
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
AutoRegionProposal suggestRegions(const TetMesh& mesh, const FreeDofs& freeDofs, const AutoRegionOptions& options);

}  // namespace asyncfem
