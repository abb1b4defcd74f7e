// SPDX-License-Identifier: BSD-3-Clause
// External forces that join vertices of different rates (surface contact between regions
// and L): each such term is evaluated at the states of the finest rate among its vertices,
// and its slower vertices receive the matching impulse (docs/asynchronous-integrator.md,
// "Contact between regions"). Private to the library.
#pragma once

#include <Eigen/Core>
#include <asyncfem/asyncIntegrator/regionPartition.hpp>
#include <asyncfem/dynamics/dynamicSystem.hpp>
#include <vector>

namespace asyncfem::detail {

/// The force terms of one large step split by rank (DynamicSystem::externalForceOfRank):
/// L has rank 0, region i the rank 1 + its place among the regions ordered by ratio (ties
/// by index), so a pair belongs to the finest rate among its vertices. A term of region i's
/// rank is evaluated at each of its substeps r; the force on a vertex of i enters i's
/// substep r, the force on a vertex of L enters L's force scaled by hS_i / hL, and the force
/// on a vertex of a coarser region j enters j's substep that contains i's substep, scaled by
/// hS_i / hS_j. Every term's impulse over the step then sums to zero where its forces do
/// (momentum), and a conservative term does the work of backward Euler on i's substeps
/// (energy: docs/asynchronous-integrator.md).
class RankedForces {
 public:
  /// Ranks and vertex lists for a partition (regionVertices: each region's vertices with
  /// free DOFs, ascending).
  void setPartition(const RegionPartition& partition, const FreeDofs& freeDofs,
                    const std::vector<std::vector<int>>& regionVertices);
  /// Sets every force to zero for a step: L's (|L|) and each region's (|S_i| x m_i).
  void clear();
  /// L's own terms (rank 0) at (time, u, v), into large; their derivatives into jacobian
  /// where not null (DynamicSystem::externalForceOfRank).
  void addLarge(const DynamicSystem& system, double time, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                VertexJacobian* jacobian = nullptr);
  /// Region i's terms at its substep r (1..m_i) at (time, u, v): the whole state, L and the
  /// other regions where they are at that time; their derivatives into jacobian where not null.
  void addRegion(const DynamicSystem& system, int i, int r, double time, const Eigen::VectorXd& u,
                 const Eigen::VectorXd& v, VertexJacobian* jacobian = nullptr);
  /// Region i's terms' derivatives alone at (time, u, v) (i = -1: L's own terms).
  void jacobian(const DynamicSystem& system, int i, double time, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                VertexJacobian& jacobian) const;

  /// Forces (not impulses): L's impulse over the step is hL large, region i's at substep r
  /// hS_i region[i].col(r - 1).
  Eigen::VectorXd large;
  std::vector<Eigen::MatrixXd> region;

 private:
  /// Region i's terms (i = -1: L's own) at (time, u, v), added to forces.
  void evaluate(const DynamicSystem& system, int i, double time, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                Eigen::VectorXd& forces, VertexJacobian* jacobian) const;

  const RegionPartition* partition_ = nullptr;
  const std::vector<std::vector<int>>* regionVertices_ = nullptr;
  std::vector<int> rank_, regionRank_, largeVertices_;
  Eigen::VectorXd force_;
  mutable Eigen::VectorXd scratch_;  // jacobian()'s forces, not kept
};

}  // namespace asyncfem::detail
