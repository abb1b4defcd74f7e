// SPDX-License-Identifier: BSD-3-Clause
// The cost model of proposed regions (RegionProposalCost, estimateAsyncCost): flops of an
// asynchronous large step against single-rate, from CHOLMOD's symbolic analyses.
#include <algorithm>
#include <asyncfem/asyncIntegrator/regionProposal.hpp>
#include <asyncfem/sparseSolver/sparseSolver.hpp>
#include <cstdio>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace asyncfem {

namespace {

/// Cost of a Cholesky factor, from CHOLMOD's symbolic analysis (METIS ordering) of the
/// pattern: the factor's non-zeros and the flops of a numeric factorization.
struct FactorCost {
  double entries = 0.0;
  double flops = 0.0;
  double solveFlops() const { return 4.0 * entries; }
};

/// The DOF-level pattern of the stiffness coupling (3 x 3 blocks of vertex pairs that share
/// an element, diagonals included) restricted to `dofs`, plus a dense block over each of
/// `denseBlocks` (DOFs in `dofs`), analysed symbolically; also returns its non-zeros.
FactorCost analyseBlock(const std::vector<std::pair<int, int>>& vertexPairs, int numVertices,
                        const std::vector<int>& dofs, const std::vector<const std::vector<int>*>& denseBlocks,
                        double* patternEntries) {
  FactorCost cost;
  if (patternEntries != nullptr) *patternEntries = 0.0;
  if (dofs.empty()) return cost;
  std::vector<int> local(static_cast<std::size_t>(3 * numVertices), -1);
  for (std::size_t k = 0; k < dofs.size(); ++k) local[static_cast<std::size_t>(dofs[k])] = static_cast<int>(k);
  std::vector<Eigen::Triplet<double>> entries;
  const auto add = [&](int a, int b) {
    const int i = local[static_cast<std::size_t>(a)], j = local[static_cast<std::size_t>(b)];
    if (i >= 0 && j >= 0) entries.emplace_back(i, j, 1.0);
  };
  for (const auto& [x, y] : vertexPairs)
    for (int c = 0; c < 3; ++c)
      for (int d = 0; d < 3; ++d) {
        add(3 * x + c, 3 * y + d);
        if (x != y) add(3 * y + d, 3 * x + c);
      }
  for (const std::vector<int>* block : denseBlocks)
    for (int a : *block)
      for (int b : *block) add(a, b);
  const auto n = static_cast<Eigen::Index>(dofs.size());
  Eigen::SparseMatrix<double> pattern(n, n);
  pattern.setFromTriplets(entries.begin(), entries.end(), [](double a, double) { return a; });
  if (patternEntries != nullptr) *patternEntries = static_cast<double>(pattern.nonZeros());
  const std::unique_ptr<SparseSolver> solver = makeSparseSolver(SolverKind::cholmod);
  solver->analyzePattern(pattern);
  cost.entries = static_cast<double>(solver->stats().factorNonZeros);
  cost.flops = solver->stats().factorFlops;
  return cost;
}

}  // namespace

RegionProposalCost estimateAsyncCost(const TetMesh& mesh, const FreeDofs& freeDofs,
                                     const std::vector<AsyncRegion>& regions, bool nonlinear, double costMargin) {
  RegionProposalCost cost;
  cost.evaluated = true;
  const RegionPartition partition(mesh, freeDofs, regions);
  const int nv = mesh.numVertices();
  std::vector<std::pair<int, int>> pairs;
  pairs.reserve(static_cast<std::size_t>(
      (mesh.verticesPerElement() * (mesh.verticesPerElement() - 1) / 2 * mesh.numElements()) + nv));
  for (int v = 0; v < nv; ++v) pairs.emplace_back(v, v);
  for (int e = 0; e < mesh.numElements(); ++e)
    for (int a = 0; a < mesh.verticesPerElement(); ++a)
      for (int b = a + 1; b < mesh.verticesPerElement(); ++b) {
        const int x = mesh.elementVertex(e, a), y = mesh.elementVertex(e, b);
        pairs.emplace_back(std::min(x, y), std::max(x, y));
      }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  std::vector<int> allFree;
  for (int dof = 0; dof < 3 * nv; ++dof)
    if (!freeDofs.isFixed(dof)) allFree.push_back(dof);
  const int numRegions = partition.numRegions();
  const double nL = static_cast<double>(partition.largeDofs().size());
  cost.freeDofs = freeDofs.numFree();
  cost.largeDofs = static_cast<int>(nL);
  // Single-rate: one back-substitution (plus the K v and f_int products) per step;
  // nonlinear: a numeric factorization too.
  double allEntries = 0.0;
  const FactorCost full = analyseBlock(pairs, nv, allFree, {}, &allEntries);
  const double singleStep = full.solveFlops() + 4.0 * allEntries + (nonlinear ? full.flops : 0.0);
  int maxRatio = 1;
  for (int i = 0; i < numRegions; ++i) maxRatio = std::max(maxRatio, partition.ratio(i));
  cost.singleRateSubsteps = maxRatio;
  cost.singleRateFlops = maxRatio * singleStep;
  cost.singleRateSetupFlops = full.flops;
  // Async: H^{LL*} is A^L plus a dense I_i x I_i block per region; per region m_i
  // forward-substitution solves, and the recovery (a second forward substitution or the
  // dense 4 |S| q products, whichever is cheaper).
  double zSolves = 0.0, regionFactorFlops = 0.0, regionSteps = 0.0;
  std::vector<const std::vector<int>*> interfaces;
  for (int i = 0; i < numRegions; ++i) {
    const double s = static_cast<double>(partition.regionDofs(i).size());
    const double q = static_cast<double>(partition.interfaceDofs(i).size());
    const double m = partition.ratio(i);
    cost.interfaceDofs += static_cast<int>(q);
    interfaces.push_back(&partition.interfaceDofs(i));
    double entries = 0.0;
    const FactorCost region = analyseBlock(pairs, nv, partition.regionDofs(i), {}, &entries);
    const double substitution = m * (region.solveFlops() + 4.0 * entries);
    regionSteps += substitution + std::min(substitution, 4.0 * s * q);
    zSolves += m * q * (region.solveFlops() + 4.0 * entries);
    regionFactorFlops += region.flops;
  }
  double largeEntries = 0.0;
  const FactorCost schur = analyseBlock(pairs, nv, partition.largeDofs(), interfaces, &largeEntries);
  const double asyncSetup = regionFactorFlops + zSolves + schur.flops;
  cost.asyncSetupFlops = asyncSetup;
  cost.asyncFlops = schur.solveFlops() + regionSteps + 4.0 * allEntries + (nonlinear ? asyncSetup : 0.0);
  cost.asyncCheaper = cost.asyncFlops < costMargin * cost.singleRateFlops;
  char line[400];
  std::snprintf(line, sizeof line,
                "%s: async %.3g Mflop per large step (%d regions, %d interface DOFs, |L| = %d) against %.3g Mflop for "
                "%d single-rate step%s at hL/%d (ratio %.2f); set-up %.3g against %.3g Mflop",
                cost.asyncCheaper ? "async regions kept" : "regions withdrawn, single-rate", 1e-6 * cost.asyncFlops,
                numRegions, cost.interfaceDofs, cost.largeDofs, 1e-6 * cost.singleRateFlops, maxRatio,
                maxRatio == 1 ? "" : "s", maxRatio, cost.ratio(), 1e-6 * cost.asyncSetupFlops,
                1e-6 * cost.singleRateSetupFlops);
  cost.decision = line;
  return cost;
}

}  // namespace asyncfem
