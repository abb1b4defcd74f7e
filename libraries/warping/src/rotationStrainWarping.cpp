// SPDX-License-Identifier: BSD-3-Clause
#include <Eigen/SparseCore>
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/volumetricMesh/queries.hpp>
#include <asyncfem/warping/rotationStrainWarping.hpp>
#include <numeric>
#include <string>

#include "detail/elementGeometry.hpp"

namespace asyncfem {

namespace {

// Smallest loop (elements or vertices) run on several OpenMP threads.
constexpr int kParallelThreshold = 8192;

// Union-find with path halving; the representative is the lowest id of the set, so
// component numbering (by representative order) is deterministic.
int findRoot(std::vector<int>& parent, int v) {
  while (parent[static_cast<std::size_t>(v)] != v) {
    parent[static_cast<std::size_t>(v)] = parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(v)])];
    v = parent[static_cast<std::size_t>(v)];
  }
  return v;
}

void unite(std::vector<int>& parent, int a, int b) {
  a = findRoot(parent, a);
  b = findRoot(parent, b);
  if (a == b) {
    return;
  }
  if (a < b) {
    parent[static_cast<std::size_t>(b)] = a;
  } else {
    parent[static_cast<std::size_t>(a)] = b;
  }
}

/// fixed[v]: v is in fixedVertices (ValidationError naming one out of [0, numVertices)).
std::vector<bool> fixedMask(const std::vector<int>& fixedVertices, int numVertices) {
  std::vector<bool> fixed(static_cast<std::size_t>(numVertices), false);
  for (const int v : fixedVertices) {
    if (v < 0 || v >= numVertices) {
      throw ValidationError("rotation-strain warping: fixed vertex " + std::to_string(v) + " out of range [0, " +
                            std::to_string(numVertices) + ")");
    }
    fixed[static_cast<std::size_t>(v)] = true;
  }
  return fixed;
}

/// For elements of K vertices: (F_e - I) int_e grad N_a with F_e = exp([omega_e]x) (I + S_e)
/// from the centre gradient, into columns K e + a of out.
template <int K>
void targetRightHandSides(const Eigen::Map<const Eigen::Matrix3Xd>& u, const Eigen::MatrixXi& elements,
                          const Eigen::Matrix3Xd& centreGradients, const Eigen::Matrix3Xd& integratedGradients,
                          Eigen::Matrix<double, 3, Eigen::Dynamic>& out) {
  const int numElements = static_cast<int>(elements.cols());
  // Threads only pay off beyond a few thousand elements (a parallel region costs about
  // as much as 1000 elements here, and far more when the cores are oversubscribed).
#pragma omp parallel for schedule(static) if (numElements >= kParallelThreshold)
  for (int e = 0; e < numElements; ++e) {
    Eigen::Matrix<double, 3, K> vertexDisplacements;
    for (int a = 0; a < K; ++a) {
      vertexDisplacements.col(a) = u.col(elements(a, e));
    }
    const Eigen::Matrix3d gradient = vertexDisplacements * centreGradients.middleCols<K>(K * e).transpose();
    const Eigen::Matrix3d skew = 0.5 * (gradient - gradient.transpose());
    const Eigen::Matrix3d strain = 0.5 * (gradient + gradient.transpose());
    const Eigen::Matrix3d rotation = detail::rotationFromVector(detail::axial(skew));
    // R (I + S) - I = (R - I) + R S, written so that u = 0 gives exactly zero.
    const Eigen::Matrix3d target = (rotation - Eigen::Matrix3d::Identity()) + rotation * strain;
    out.middleCols<K>(K * e) = target * integratedGradients.middleCols<K>(K * e);
  }
}

}  // namespace

RotationStrainWarping::RotationStrainWarping(const TetMesh& mesh, const std::vector<int>& fixedVertices,
                                             SolverKind solverKind)
    : numVertices_(mesh.numVertices()),
      numElements_(mesh.numElements()),
      verticesPerElement_(mesh.verticesPerElement()),
      elements_(mesh.connectivity()) {
  const detail::ElementGeometry geometry = detail::elementGeometry(mesh);
  centreGradients_ = geometry.centreGradients;
  integratedGradients_ = geometry.integratedGradients;
  const auto n = static_cast<std::size_t>(numVertices_);
  const std::vector<bool> fixed = fixedMask(fixedVertices, numVertices_);
  std::vector<bool> used(n, false);
  for (int e = 0; e < numElements_; ++e) {
    for (int a = 0; a < verticesPerElement_; ++a) {
      used[static_cast<std::size_t>(elements_(a, e))] = true;
    }
  }
  findComponents(used, fixed);
  std::vector<int> unknownIndex(n, -1);
  std::vector<int> constrainedIndex(n, -1);
  numberVertices(used, fixed, unknownIndex, constrainedIndex);
  factorLaplacian(mesh, geometry, unknownIndex, constrainedIndex, solverKind);
  buildGatherMap(mesh);
  elementRightHandSides_.resize(3, static_cast<Eigen::Index>(verticesPerElement_) * numElements_);
}

/// Connected components of the used vertices (through shared elements), numbered by
/// their lowest vertex; a component without a fixed vertex is pinned.
void RotationStrainWarping::findComponents(const std::vector<bool>& used, const std::vector<bool>& fixed) {
  const auto n = static_cast<std::size_t>(numVertices_);
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  for (int e = 0; e < numElements_; ++e) {
    for (int a = 1; a < verticesPerElement_; ++a) {
      unite(parent, elements_(0, e), elements_(a, e));
    }
  }
  component_.assign(n, -1);
  std::vector<int> rootComponent(n, -1);
  for (int v = 0; v < numVertices_; ++v) {
    if (!used[static_cast<std::size_t>(v)]) {
      unusedVertices_.push_back(v);
      continue;
    }
    const int root = findRoot(parent, v);
    int& id = rootComponent[static_cast<std::size_t>(root)];
    if (id < 0) {
      id = static_cast<int>(componentVertices_.size());
      componentVertices_.emplace_back();
      componentPinned_.push_back(true);
    }
    component_[static_cast<std::size_t>(v)] = id;
    componentVertices_[static_cast<std::size_t>(id)].push_back(v);
    if (fixed[static_cast<std::size_t>(v)]) {
      componentPinned_[static_cast<std::size_t>(id)] = false;
    }
  }
}

/// Constrained: fixed vertices, and the lowest vertex of every pinned component; the
/// other used vertices are unknowns. Both lists ascend.
void RotationStrainWarping::numberVertices(const std::vector<bool>& used, const std::vector<bool>& fixed,
                                           std::vector<int>& unknownIndex, std::vector<int>& constrainedIndex) {
  std::vector<bool> constrained(static_cast<std::size_t>(numVertices_), false);
  for (std::size_t c = 0; c < componentVertices_.size(); ++c) {
    if (componentPinned_[c]) {
      constrained[static_cast<std::size_t>(componentVertices_[c].front())] = true;
    }
  }
  for (int v = 0; v < numVertices_; ++v) {
    const auto sv = static_cast<std::size_t>(v);
    if (!used[sv]) {
      continue;
    }
    if (constrained[sv] || fixed[sv]) {
      constrainedIndex[sv] = static_cast<int>(constrainedVertices_.size());
      constrainedVertices_.push_back(v);
    } else {
      unknownIndex[sv] = static_cast<int>(unknownVertices_.size());
      unknownVertices_.push_back(v);
    }
  }
}

/// L_ab = sum_e int_e grad N_a . grad N_b, split into the unknown-unknown block (factored)
/// and the unknown-constrained block (moves the constrained values to the right side).
void RotationStrainWarping::factorLaplacian(const TetMesh& mesh, const detail::ElementGeometry& geometry,
                                            const std::vector<int>& unknownIndex,
                                            const std::vector<int>& constrainedIndex, SolverKind solverKind) {
  const int k = verticesPerElement_;
  std::vector<Eigen::Triplet<double>> unknownTriplets;
  std::vector<Eigen::Triplet<double>> couplingTriplets;
  unknownTriplets.reserve(static_cast<std::size_t>(numElements_) * k * k);
  for (int e = 0; e < numElements_; ++e) {
    const Eigen::MatrixXd local = detail::elementLaplacian(mesh, geometry, e);
    for (int a = 0; a < k; ++a) {
      const int row = unknownIndex[static_cast<std::size_t>(elements_(a, e))];
      if (row < 0) {
        continue;
      }
      for (int b = 0; b < k; ++b) {
        const auto vb = static_cast<std::size_t>(elements_(b, e));
        if (unknownIndex[vb] >= 0) {
          unknownTriplets.emplace_back(row, unknownIndex[vb], local(a, b));
        } else {
          couplingTriplets.emplace_back(row, constrainedIndex[vb], local(a, b));
        }
      }
    }
  }
  const int numUnknown = static_cast<int>(unknownVertices_.size());
  Eigen::SparseMatrix<double> laplacian(numUnknown, numUnknown);
  laplacian.setFromTriplets(unknownTriplets.begin(), unknownTriplets.end());
  laplacian.makeCompressed();
  laplacianUnknownConstrained_.resize(numUnknown, static_cast<Eigen::Index>(constrainedVertices_.size()));
  laplacianUnknownConstrained_.setFromTriplets(couplingTriplets.begin(), couplingTriplets.end());
  laplacianUnknownConstrained_.makeCompressed();
  solver_ = makeSparseSolver(solverKind);
  if (numUnknown > 0) {
    solver_->compute(laplacian);
  }
}

/// Gather map for the right-hand side: for each vertex, (element, local index) pairs in
/// ascending element order, so every b_a is summed in one fixed order.
void RotationStrainWarping::buildGatherMap(const TetMesh& mesh) {
  const VertexElementAdjacency adjacency = vertexElementAdjacency(mesh);
  adjacencyOffsets_ = adjacency.offsets;
  adjacencySlots_.resize(adjacency.elements.size());
  for (int v = 0; v < numVertices_; ++v) {
    for (int k = adjacency.offsets[static_cast<std::size_t>(v)]; k < adjacency.offsets[static_cast<std::size_t>(v) + 1];
         ++k) {
      const int e = adjacency.elements[static_cast<std::size_t>(k)];
      int local = 0;
      while (elements_(local, e) != v) {
        ++local;
      }
      adjacencySlots_[static_cast<std::size_t>(k)] = (verticesPerElement_ * e) + local;
    }
  }
}

RotationStrainWarping::~RotationStrainWarping() = default;
RotationStrainWarping::RotationStrainWarping(RotationStrainWarping&&) noexcept = default;
RotationStrainWarping& RotationStrainWarping::operator=(RotationStrainWarping&&) noexcept = default;

const SolverStats& RotationStrainWarping::solverStats() const { return solver_->stats(); }

Eigen::VectorXd RotationStrainWarping::warp(const Eigen::Ref<const Eigen::VectorXd>& displacement) {
  if (displacement.size() != 3 * static_cast<Eigen::Index>(numVertices_)) {
    throw Error("rotation-strain warping: displacement has " + std::to_string(displacement.size()) +
                " entries, expected 3 x " + std::to_string(numVertices_));
  }
  const Eigen::Map<const Eigen::Matrix3Xd> u(displacement.data(), 3, numVertices_);
  elementPass(u);
  gatherRightHandSide(u);
  Eigen::VectorXd warped = displacement;  // constrained and unused vertices keep theirs
  const auto numUnknown = static_cast<Eigen::Index>(unknownVertices_.size());
  if (numUnknown > 0) {
    solver_->solve(rightHandSide_, solution_);
    for (Eigen::Index k = 0; k < numUnknown; ++k) {
      warped.segment<3>(3 * static_cast<Eigen::Index>(unknownVertices_[static_cast<std::size_t>(k)])) =
          solution_.row(k).transpose();
    }
  }
  shiftPinnedComponents(u, warped);
  return warped;
}

/// F_e = exp([omega_e]x) (I + S_e) of every element; its contribution (F_e - I) int_e grad N_a
/// to the right-hand side goes to elementRightHandSides_.
void RotationStrainWarping::elementPass(const Eigen::Map<const Eigen::Matrix3Xd>& u) {
  if (verticesPerElement_ == 8) {
    targetRightHandSides<8>(u, elements_, centreGradients_, integratedGradients_, elementRightHandSides_);
  } else {
    targetRightHandSides<4>(u, elements_, centreGradients_, integratedGradients_, elementRightHandSides_);
  }
}

/// Gathers b at the unknown vertices into rightHandSide_ and moves the constrained values
/// to the right side.
void RotationStrainWarping::gatherRightHandSide(const Eigen::Map<const Eigen::Matrix3Xd>& u) {
  const auto numUnknown = static_cast<Eigen::Index>(unknownVertices_.size());
  const auto numConstrained = static_cast<Eigen::Index>(constrainedVertices_.size());
  rightHandSide_.resize(numUnknown, 3);
#pragma omp parallel for schedule(static) if (numUnknown >= kParallelThreshold)
  for (Eigen::Index k = 0; k < numUnknown; ++k) {
    const auto v = static_cast<std::size_t>(unknownVertices_[static_cast<std::size_t>(k)]);
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int s = adjacencyOffsets_[v]; s < adjacencyOffsets_[v + 1]; ++s) {
      sum += elementRightHandSides_.col(adjacencySlots_[static_cast<std::size_t>(s)]);
    }
    rightHandSide_.row(k) = sum.transpose();
  }
  if (numConstrained > 0 && numUnknown > 0) {
    Eigen::MatrixXd constrainedValues(numConstrained, 3);
    for (Eigen::Index k = 0; k < numConstrained; ++k) {
      constrainedValues.row(k) = u.col(constrainedVertices_[static_cast<std::size_t>(k)]).transpose();
    }
    rightHandSide_.noalias() -= laplacianUnknownConstrained_ * constrainedValues;
  }
}

/// Translation-free (pinned) components: shifted to match the mean displacement of the
/// linear input.
void RotationStrainWarping::shiftPinnedComponents(const Eigen::Map<const Eigen::Matrix3Xd>& u,
                                                  Eigen::VectorXd& warped) const {
  for (std::size_t c = 0; c < componentVertices_.size(); ++c) {
    if (!componentPinned_[c]) {
      continue;
    }
    Eigen::Vector3d shift = Eigen::Vector3d::Zero();
    for (const int v : componentVertices_[c]) {
      shift += u.col(v) - warped.segment<3>(3 * static_cast<Eigen::Index>(v));
    }
    shift /= static_cast<double>(componentVertices_[c].size());
    for (const int v : componentVertices_[c]) {
      warped.segment<3>(3 * static_cast<Eigen::Index>(v)) += shift;
    }
  }
}

}  // namespace asyncfem
