// SPDX-License-Identifier: BSD-3-Clause
#include "detail/rankedForces.hpp"

#include <algorithm>
#include <numeric>

namespace asyncfem::detail {

void RankedForces::setPartition(const RegionPartition& partition, const FreeDofs& freeDofs,
                                const std::vector<std::vector<int>>& regionVertices) {
  partition_ = &partition;
  regionVertices_ = &regionVertices;
  const int count = partition.numRegions();
  std::vector<int> order(static_cast<std::size_t>(count));
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return partition.ratio(a) < partition.ratio(b); });
  regionRank_.assign(static_cast<std::size_t>(count), 0);
  for (std::size_t k = 0; k < order.size(); ++k)
    regionRank_[static_cast<std::size_t>(order[k])] = static_cast<int>(k) + 1;
  const std::vector<int>& vertexRegion = partition.vertexRegion();
  rank_.assign(vertexRegion.size(), 0);
  largeVertices_.clear();
  for (std::size_t v = 0; v < vertexRegion.size(); ++v) {
    const int region = vertexRegion[v];
    if (region >= 0) {
      rank_[v] = regionRank_[static_cast<std::size_t>(region)];
      continue;
    }
    const auto dof = static_cast<int>(3 * v);
    if (!freeDofs.isFixed(dof) || !freeDofs.isFixed(dof + 1) || !freeDofs.isFixed(dof + 2))
      largeVertices_.push_back(static_cast<int>(v));
  }
}

void RankedForces::clear() {
  large.setZero(static_cast<Eigen::Index>(partition_->largeDofs().size()));
  region.resize(static_cast<std::size_t>(partition_->numRegions()));
  for (int i = 0; i < partition_->numRegions(); ++i)
    region[static_cast<std::size_t>(i)].setZero(static_cast<Eigen::Index>(partition_->regionDofs(i).size()),
                                                partition_->ratio(i));
}

void RankedForces::addLarge(const DynamicSystem& system, double time, const Eigen::VectorXd& u,
                            const Eigen::VectorXd& v, VertexJacobian* jacobian) {
  force_.setZero(u.size());
  evaluate(system, -1, time, u, v, force_, jacobian);
  const std::vector<int>& dofs = partition_->largeDofs();
  for (std::size_t k = 0; k < dofs.size(); ++k) large[static_cast<Eigen::Index>(k)] += force_[dofs[k]];
}

void RankedForces::addRegion(const DynamicSystem& system, int i, int r, double time, const Eigen::VectorXd& u,
                             const Eigen::VectorXd& v, VertexJacobian* jacobian) {
  const auto at = static_cast<std::size_t>(i);
  force_.setZero(u.size());
  evaluate(system, i, time, u, v, force_, jacobian);
  const int m = partition_->ratio(i);
  // L: hL (share) = hS_i f, share = f / m.
  const std::vector<int>& largeDofs = partition_->largeDofs();
  for (std::size_t k = 0; k < largeDofs.size(); ++k) large[static_cast<Eigen::Index>(k)] += force_[largeDofs[k]] / m;
  for (int j = 0; j < partition_->numRegions(); ++j) {
    const std::vector<int>& dofs = partition_->regionDofs(j);
    Eigen::MatrixXd& into = region[static_cast<std::size_t>(j)];
    if (j == i) {
      for (std::size_t k = 0; k < dofs.size(); ++k) into(static_cast<Eigen::Index>(k), r - 1) += force_[dofs[k]];
      continue;
    }
    if (regionRank_[static_cast<std::size_t>(j)] > regionRank_[at]) continue;  // finer: none of its pairs are i's
    // Region j's substep c containing i's substep r: (c - 1) hS_j < r hS_i <= c hS_j.
    const int mj = partition_->ratio(j);
    const int c = ((r * mj) + m - 1) / m;
    const double scale = static_cast<double>(mj) / m;
    for (std::size_t k = 0; k < dofs.size(); ++k) into(static_cast<Eigen::Index>(k), c - 1) += scale * force_[dofs[k]];
  }
}

void RankedForces::jacobian(const DynamicSystem& system, int i, double time, const Eigen::VectorXd& u,
                            const Eigen::VectorXd& v, VertexJacobian& jacobian) const {
  scratch_.setZero(u.size());
  evaluate(system, i, time, u, v, scratch_, &jacobian);
}

void RankedForces::evaluate(const DynamicSystem& system, int i, double time, const Eigen::VectorXd& u,
                            const Eigen::VectorXd& v, Eigen::VectorXd& forces, VertexJacobian* jacobian) const {
  if (i < 0) {
    system.externalForceOfRank(time, u, v, largeVertices_, rank_, 0, forces, jacobian);
    return;
  }
  const auto at = static_cast<std::size_t>(i);
  system.externalForceOfRank(time, u, v, (*regionVertices_)[at], rank_, regionRank_[at], forces, jacobian);
}

}  // namespace asyncfem::detail
