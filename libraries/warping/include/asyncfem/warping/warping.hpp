// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <memory>
#include <string>
#include <vector>

namespace asyncfem {

/// Geometric post-process applied to a linear-FEM displacement field before display.
enum class WarpingKind {
  none,            ///< the linear displacement as it is
  rotationStrain,  ///< RotationStrainWarping (per-element rotation + strain, Poisson solve)
  modal,           ///< ModalWarping (per-vertex rotation from the curl)
};
/// "none", "rotation-strain", "modal".
std::string toString(WarpingKind kind);
/// Inverse of toString; throws asyncfem::Error listing the valid names.
WarpingKind parseWarpingKind(const std::string& name);

/// A warping method bound to one mesh: everything that depends only on the rest shape
/// (shape-function gradients, volumes, factorizations) is computed by the constructor of
/// the implementation, so warp() is the per-frame cost only.
///
/// Both vectors are stacked 3n displacements (x0 y0 z0 x1 ...; length units of the
/// mesh): rest position + warped displacement = warped position. warp() is not required
/// to be thread-safe: use one object per thread.
class Warping {
 public:
  virtual ~Warping() = default;
  virtual WarpingKind kind() const = 0;
  /// Number of vertices n of the mesh the object was built for.
  virtual int numVertices() const = 0;
  /// Warped displacement for a linear displacement (both size 3n; asyncfem::Error
  /// otherwise).
  virtual Eigen::VectorXd warp(const Eigen::Ref<const Eigen::VectorXd>& displacement) = 0;
};

/// Creates the warping of the given kind for mesh. fixedVertices (0-based, any order) are
/// held at their given displacement by RotationStrainWarping; ModalWarping and
/// WarpingKind::none (identity) ignore them. Throws what the constructors throw.
std::unique_ptr<Warping> makeWarping(WarpingKind kind, const TetMesh& mesh, const std::vector<int>& fixedVertices = {});

/// Rest positions plus a stacked 3n displacement, as a 3 x n matrix of positions.
Eigen::Matrix3Xd deformedPositions(const TetMesh& mesh, const Eigen::Ref<const Eigen::VectorXd>& displacement);

}  // namespace asyncfem
