// SPDX-License-Identifier: BSD-3-Clause
// The stable coupling's large step solved from its per-substep definition
// (docs/asynchronous-integrator.md, "Stable coupling"), the independent reference the
// structured solve is checked against.
#pragma once

#include <Eigen/Dense>
#include <algorithm>
#include <asyncfem/asyncIntegrator/asyncBackwardEuler.hpp>
#include <asyncfem/stiffnessMatrix/elementMatrices.hpp>
#include <map>
#include <utility>
#include <vector>

#include "asyncTestSystem.hpp"

namespace asyncfem::test {

/// One large step of the stable coupling solved from its definition (the per-substep
/// equations of docs/asynchronous-integrator.md, "Stable coupling", written with positions
/// and velocities, no block formulas): the residual is affine in the unknowns
/// (v^{S_i}_1..v^{S_i}_{m_i} for every region, then v^L_m), so its dense Jacobian is built
/// column by column and the system solved by LU. Linear forces; K_I of each region is summed
/// here from the mesh's element stiffness matrices (tetrahedra or hexahedra). The external force is evaluated at each
/// equation's own state (a fast region's substep r at its state after substep r, L at the end
/// of the step: implicit contact's definition); where it depends on the state (penalty
/// contact, piecewise affine) the residual is no longer affine and the step takes Newton
/// iterations with a difference Jacobian (exact within one contact set) until the update is
/// round-off. Where the system splits its force by rank (DynamicSystem::externalForceOfRank:
/// surface contact; one region here, rank 1, L rank 0), the pairs that join the region are
/// taken at its substeps, their force on L's vertices as hS times their sum over the
/// substeps, and L's own terms at the end of the step (docs/asynchronous-integrator.md,
/// "Contact between regions").
class DefinitionStep {
 public:
  DefinitionStep(const TetMesh& mesh, const DynamicSystem& system, std::vector<AsyncRegion> regions)
      : mesh_(mesh), system_(system), regions_(std::move(regions)) {
    const std::vector<int>& free = system.freeDofs.freeToFull();
    const int n = mesh.numDofs();
    std::vector<int> vertexRegion(static_cast<std::size_t>(mesh.numVertices()), -1);
    for (std::size_t i = 0; i < regions_.size(); ++i)
      for (int v : regions_[i].vertices) vertexRegion[static_cast<std::size_t>(v)] = static_cast<int>(i);
    const int nf = static_cast<int>(free.size());
    DenseFreeMatrices dense = denseFreeMatrices(system);
    M_ = std::move(dense.M);
    K_ = std::move(dense.K);
    D_ = std::move(dense.D);
    regionOfFree_.resize(static_cast<std::size_t>(nf));
    for (int a = 0; a < nf; ++a) {
      const int region = vertexRegion[static_cast<std::size_t>(free[a] / 3)];
      regionOfFree_[static_cast<std::size_t>(a)] = region;
      (region < 0 ? large_ : fast_[region]).push_back(a);
    }
    // Ranks for a system that splits its force (one region: its vertices rank 1, the rest 0),
    // and each rank's vertices with a free DOF.
    vertexRank_.assign(static_cast<std::size_t>(mesh.numVertices()), 0);
    rankVertices_.assign(2, {});
    for (int v = 0; v < mesh.numVertices(); ++v) {
      const int rank = vertexRegion[static_cast<std::size_t>(v)] >= 0 ? 1 : 0;
      vertexRank_[static_cast<std::size_t>(v)] = rank;
      bool free = false;
      for (int c = 0; c < 3; ++c) free = free || !system.freeDofs.isFixed((3 * v) + c);
      if (free) rankVertices_[static_cast<std::size_t>(rank)].push_back(v);
    }
    // K_I of region i: the elements with a vertex in S_i and a vertex in no fast region.
    std::vector<int> freeIndex(static_cast<std::size_t>(n), -1);
    for (int a = 0; a < nf; ++a) freeIndex[static_cast<std::size_t>(free[a])] = a;
    for (std::size_t i = 0; i < regions_.size(); ++i) interfaceK_.push_back(Eigen::MatrixXd::Zero(nf, nf));
    for (int e = 0; e < mesh.numElements(); ++e) {
      int fast = -1;
      bool large = false;
      for (int a = 0; a < mesh.verticesPerElement(); ++a) {
        const int region = vertexRegion[static_cast<std::size_t>(mesh.elementVertex(e, a))];
        if (region >= 0) fast = region;
        large = large || region < 0;
      }
      if (fast < 0 || !large) continue;
      const Eigen::MatrixXd ke = elementLinearStiffness(mesh, e);
      for (int p = 0; p < ke.rows(); ++p)
        for (int q = 0; q < ke.cols(); ++q) {
          const int a = freeIndex[static_cast<std::size_t>(3 * mesh.elementVertex(e, p / 3) + p % 3)];
          const int b = freeIndex[static_cast<std::size_t>(3 * mesh.elementVertex(e, q / 3) + q % 3)];
          if (a >= 0 && b >= 0) interfaceK_[static_cast<std::size_t>(fast)](a, b) += ke(p, q);
        }
    }
  }

  /// One large step hL from (u, v) at time t (full vectors), in place.
  void step(double hL, double t, Eigen::VectorXd& u, Eigen::VectorXd& v) const {
    const FreeDofs& dofs = system_.freeDofs;
    const Eigen::VectorXd u0 = dofs.restrict(u), v0 = dofs.restrict(v);
    int unknowns = static_cast<int>(large_.size());
    for (std::size_t i = 0; i < regions_.size(); ++i)
      unknowns += regions_[i].ratio * static_cast<int>(fast_.at(static_cast<int>(i)).size());
    // Velocities are ~1: a difference step of 1e-7 stays within one contact set.
    constexpr double kDifference = 1e-7;
    Eigen::VectorXd z = Eigen::VectorXd::Zero(unknowns);
    for (int iteration = 0; iteration < 30; ++iteration) {
      const Eigen::VectorXd r0 = residual(z, hL, t, u0, v0, nullptr, nullptr);
      Eigen::MatrixXd jacobian(unknowns, unknowns);
      for (int j = 0; j < unknowns; ++j) {
        Eigen::VectorXd shifted = z;
        shifted[j] += kDifference;
        jacobian.col(j) = (residual(shifted, hL, t, u0, v0, nullptr, nullptr) - r0) / kDifference;
      }
      const Eigen::VectorXd update = jacobian.partialPivLu().solve(-r0);
      z += update;
      if (update.lpNorm<Eigen::Infinity>() <= 1e-15 * std::max(1.0, z.lpNorm<Eigen::Infinity>())) break;
    }
    Eigen::VectorXd uEnd, vEnd;
    residual(z, hL, t, u0, v0, &uEnd, &vEnd);
    u = dofs.expand(uEnd);
    v = dofs.expand(vEnd);
  }

 private:
  // f_ext at time and the free state (u, v): all of it (rank -1), or the terms of one rank.
  Eigen::VectorXd externalForce(double time, const Eigen::VectorXd& u, const Eigen::VectorXd& v, int rank = -1) const {
    Eigen::VectorXd f = Eigen::VectorXd::Zero(mesh_.numDofs());
    if (rank >= 0) {
      system_.externalForceOfRank(time, system_.freeDofs.expand(u), system_.freeDofs.expand(v),
                                  rankVertices_[static_cast<std::size_t>(rank)], vertexRank_, rank, f, nullptr);
    } else if (system_.externalForce) {
      system_.externalForce(time, system_.freeDofs.expand(u), system_.freeDofs.expand(v), f);
    }
    return system_.freeDofs.restrict(f);
  }
  bool ranked() const { return static_cast<bool>(system_.externalForceOfRank); }

  // Residual of every equation for the unknowns z; the end state on request.
  Eigen::VectorXd residual(const Eigen::VectorXd& z, double hL, double t, const Eigen::VectorXd& u0,
                           const Eigen::VectorXd& v0, Eigen::VectorXd* uEnd, Eigen::VectorXd* vEnd) const {
    const Eigen::Index nf = u0.size();
    Eigen::VectorXd out(z.size());
    // v^L_m, and L's positions u^L_r = u^L_0 + r hS v^L_m (L at its end-of-step velocity).
    const Eigen::Index largeOffset = z.size() - static_cast<Eigen::Index>(large_.size());
    Eigen::VectorXd vLarge = v0;  // only the L entries are used
    for (std::size_t k = 0; k < large_.size(); ++k) vLarge[large_[k]] = z[largeOffset + static_cast<Eigen::Index>(k)];
    Eigen::VectorXd uFinal = u0 + hL * vLarge, vFinal = vLarge;
    // L's equation, accumulated over the regions' substeps.
    Eigen::VectorXd lagged =
        Eigen::VectorXd::Zero(nf);  // hS sum_r [K_I (u^L_r - u^L_0) + K^{LS} (u^S_r - u^S_0) + D^{LS} v^S_r]
    Eigen::VectorXd pairsOnLarge = Eigen::VectorXd::Zero(nf);  // hS sum_r f_pairs(r), ranked only
    Eigen::MatrixXd nonInterfaceK = K_;
    for (const Eigen::MatrixXd& ki : interfaceK_) nonInterfaceK -= ki;
    Eigen::Index offset = 0;
    for (std::size_t i = 0; i < regions_.size(); ++i) {
      const std::vector<int>& s = fast_.at(static_cast<int>(i));
      const int m = regions_[i].ratio;
      const double hS = hL / m;
      Eigen::VectorXd uPrev = u0, vPrev = v0;
      for (int r = 1; r <= m; ++r) {
        Eigen::VectorXd ur = u0, vr = v0;  // other regions stay at the step's start (they do not touch S_i)
        for (int dof : large_) {
          ur[dof] = u0[dof] + r * hS * vLarge[dof];
          vr[dof] = vLarge[dof];
        }
        for (std::size_t k = 0; k < s.size(); ++k) {
          vr[s[k]] = z[offset + static_cast<Eigen::Index>(k)];
          ur[s[k]] = uPrev[s[k]] + hS * vr[s[k]];
        }
        const Eigen::VectorXd external = externalForce(t + r * hS, ur, vr, ranked() ? 1 : -1);
        if (ranked()) pairsOnLarge += hS * external;  // L's rows: the region's pairs' share
        const Eigen::VectorXd force = external - K_ * u0 - K_ * (ur - u0) - D_ * vr;
        const Eigen::VectorXd momentum = M_ * (vr - vPrev);
        for (std::size_t k = 0; k < s.size(); ++k)
          out[offset + static_cast<Eigen::Index>(k)] = momentum[s[k]] - hS * force[s[k]];
        // What L receives from region i at this substep: its interface elements' force.
        Eigen::VectorXd onlyS = Eigen::VectorXd::Zero(nf), onlyL = Eigen::VectorXd::Zero(nf);
        for (int dof : s) onlyS[dof] = ur[dof] - u0[dof];
        for (int dof : large_) onlyL[dof] = ur[dof] - u0[dof];
        Eigen::VectorXd vS = Eigen::VectorXd::Zero(nf);
        for (int dof : s) vS[dof] = vr[dof];
        lagged += hS * (interfaceK_[i] * onlyL + K_ * onlyS + D_ * vS);
        uPrev = ur;
        vPrev = vr;
        offset += static_cast<Eigen::Index>(s.size());
      }
      for (int dof : s) {
        uFinal[dof] = uPrev[dof];
        vFinal[dof] = vPrev[dof];
      }
    }
    Eigen::VectorXd onlyL = Eigen::VectorXd::Zero(nf), vL = Eigen::VectorXd::Zero(nf);
    for (int dof : large_) {
      onlyL[dof] = uFinal[dof] - u0[dof];
      vL[dof] = vFinal[dof];
    }
    const Eigen::VectorXd endForce =
        ranked() ? Eigen::VectorXd(externalForce(t + hL, uFinal, vFinal, 0)) : externalForce(t + hL, uFinal, vFinal);
    const Eigen::VectorXd impulse =
        hL * (endForce - K_ * u0) + pairsOnLarge - hL * (nonInterfaceK * onlyL) - lagged - hL * (D_ * vL);
    const Eigen::VectorXd momentum = M_ * (vFinal - v0);
    for (std::size_t k = 0; k < large_.size(); ++k)
      out[largeOffset + static_cast<Eigen::Index>(k)] = momentum[large_[k]] - impulse[large_[k]];
    if (uEnd) *uEnd = uFinal;
    if (vEnd) *vEnd = vFinal;
    return out;
  }

  const TetMesh& mesh_;
  const DynamicSystem& system_;
  std::vector<AsyncRegion> regions_;
  Eigen::MatrixXd M_, K_, D_;
  std::vector<int> regionOfFree_;
  std::vector<int> large_;
  std::map<int, std::vector<int>> fast_;
  std::vector<Eigen::MatrixXd> interfaceK_;
  std::vector<int> vertexRank_;
  std::vector<std::vector<int>> rankVertices_;
};

}  // namespace asyncfem::test
