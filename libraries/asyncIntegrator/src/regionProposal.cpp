// SPDX-License-Identifier: BSD-3-Clause
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <asyncfem/asyncIntegrator/regionProposal.hpp>
#include <asyncfem/asyncIntegrator/runTimeRegions.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/stiffnessMatrix/elementMatrices.hpp>
#include <asyncfem/volumetricMesh/queries.hpp>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <limits>
#include <memory>
#include <numeric>
#include <string>

#include "detail/hexahedronFrequency.hpp"

namespace asyncfem {

double elementMaxFrequency(const Eigen::Matrix<double, 3, 4>& restPositions, const Material& material) {
  // With u^T K_e u = V eps:C:eps, eps = sym(sum_a u_a g_a^T), C eps = 2 mu eps + lambda tr(eps) I
  // and the lumped mass rho V / 4 on every DOF, omega_e^2 is 4 / rho times the largest
  // eigenvalue of C^{1/2} P C^{1/2} on symmetric 3x3 tensors, P eps = sym(eps G) with
  // G = sum_a g_a g_a^T (the non-zero eigenvalues of B^T C B and C^{1/2} B B^T C^{1/2}
  // agree). In the eigenbasis of G (eigenvalues g_i) P scales eps_ij by (g_i + g_j) / 2
  // and C keeps shear and normal components apart: the normal ones give the eigenvalues of
  // N = 2 mu diag(g) + lambda sqrt(g) sqrt(g)^T, the shear ones mu (g_i + g_j). Those never
  // exceed the largest eigenvalue of N's 2x2 block on i, j, which is larger by
  // lambda (g_i + g_j) / 2 + sqrt(((2 mu + lambda) (g_i - g_j) / 2)^2 + lambda^2 g_i g_j) >= 0
  // (for lambda < 0 this needs 2 mu + lambda >= -lambda, i.e. mu + lambda > 0, true for every
  // Poisson ratio in (-1, 0.5)), so omega_e^2 = 4 / rho * lambda_max(N).
  double volume = 0.0;
  const Eigen::Matrix<double, 3, 4> gradients = shapeFunctionGradients(restPositions, &volume);
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
  eigen.computeDirect(gradients * gradients.transpose(), Eigen::EigenvaluesOnly);
  const Eigen::Vector3d g = eigen.eigenvalues().cwiseMax(0.0);  // G is positive semi-definite
  const Eigen::Vector2d lame = lameParameters(material.youngsModulus, material.poissonRatio);
  const Eigen::Vector3d root = g.cwiseSqrt();
  Eigen::Matrix3d normal = lame[0] * root * root.transpose();
  normal.diagonal() += 2.0 * lame[1] * g;
  eigen.computeDirect(normal, Eigen::EigenvaluesOnly);
  return std::sqrt(std::max(0.0, 4.0 * eigen.eigenvalues().maxCoeff() / material.density));
}

Eigen::VectorXd elementMaxFrequencies(const TetMesh& mesh) {
  Eigen::VectorXd omega(mesh.numElements());
  if (mesh.isHexahedral()) {  // serial: a misshapen hexahedron throws, naming it
    for (int e = 0; e < mesh.numElements(); ++e)
      omega[e] = hexahedronMaxFrequency(mesh.hexahedronRestPositions(e), mesh.elementMaterial(e));
    return omega;
  }
#pragma omp parallel for schedule(static)
  for (int e = 0; e < mesh.numElements(); ++e) {
    omega[e] = elementMaxFrequency(mesh.elementRestPositions(e), mesh.elementMaterial(e));
  }
  return omega;
}

namespace {
/// The regular tetrahedron of unit edge length.
Eigen::Matrix<double, 3, 4> unitRegularTet() {
  Eigen::Matrix<double, 3, 4> x;
  x << 1, 1, -1, -1, 1, -1, 1, -1, 1, -1, -1, 1;
  return x / std::sqrt(8.0);  // edges of length 2 sqrt(2) before
}

double rmsEdgeLength(const Eigen::Matrix<double, 3, 4>& x) {
  double sum = 0.0;
  for (int a = 0; a < 4; ++a)
    for (int b = a + 1; b < 4; ++b) sum += (x.col(a) - x.col(b)).squaredNorm();
  return std::sqrt(sum / 6.0);
}
}  // namespace

double elementSizeFrequency(const Eigen::Matrix<double, 3, 4>& restPositions, const Material& material) {
  // omega scales as 1 / length at a fixed shape: the unit regular tet's frequency over the edge.
  const double edge = rmsEdgeLength(restPositions);
  return edge > 0.0 ? elementMaxFrequency(unitRegularTet(), material) / edge : std::numeric_limits<double>::infinity();
}

const char* toString(RegionProposalPath path) {
  switch (path) {
    case RegionProposalPath::elementCriterion:
      return "element criterion";
    case RegionProposalPath::precheck:
      return "pre-check";
    case RegionProposalPath::costCheck:
      return "cost check";
    case RegionProposalPath::modalCheck:
      return "modal check";
  }
  return "?";
}

std::vector<AsyncRegion> RegionProposal::asyncRegions() const {
  std::vector<AsyncRegion> out;
  out.reserve(regions.size());
  for (const ProposedRegion& r : regions) out.push_back(r.region);
  return out;
}

namespace {

void validate(const RegionProposalOptions& options) {
  if (!(options.largeTimestep > 0.0) || !std::isfinite(options.largeTimestep)) {
    throw ValidationError("proposed regions: the large timestep must be positive");
  }
  if (!(options.targetOmegaH > 0.0) && !(options.relativeThreshold > 1.0)) {
    throw ValidationError("proposed regions: give an omega*h target > 0 or a relative threshold > 1");
  }
  if (options.growLayers < 0 || options.maxRatio < 1) {
    throw ValidationError("proposed regions: growLayers must be >= 0 and maxRatio >= 1");
  }
}

/// The omega hL above which an element is fast: the given target, or the relative
/// threshold times the median element's omega hL.
double targetOmegaH(const Eigen::VectorXd& omega, const RegionProposalOptions& options) {
  if (options.targetOmegaH > 0.0) return options.targetOmegaH;
  std::vector<double> sorted(omega.data(), omega.data() + omega.size());
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2), sorted.end());
  const double median = sorted.empty() ? 0.0 : sorted[sorted.size() / 2];
  return options.relativeThreshold * median * options.largeTimestep;
}

/// Vertices of elements above the target, grown by growLayers rings (every vertex sharing
/// an element with a fast vertex).
std::vector<char> fastVertices(const TetMesh& mesh, const Eigen::VectorXd& omega, double hL, double target,
                               int growLayers) {
  std::vector<char> fast(static_cast<std::size_t>(mesh.numVertices()), 0);
  for (int e = 0; e < mesh.numElements(); ++e) {
    if (omega[e] * hL > target)
      for (int a = 0; a < mesh.verticesPerElement(); ++a) fast[static_cast<std::size_t>(mesh.elementVertex(e, a))] = 1;
  }
  growByRings(mesh, fast, growLayers);
  return fast;
}

/// Whether every neighbour of vertex v (through its elements) is fast, and it has any.
bool enclosed(const TetMesh& mesh, const VertexElementAdjacency& adjacency, const std::vector<char>& fast, int v) {
  const auto begin = adjacency.offsets[static_cast<std::size_t>(v)];
  const auto end = adjacency.offsets[static_cast<std::size_t>(v) + 1];
  if (begin == end) return false;
  for (int k = begin; k < end; ++k) {
    const int e = adjacency.elements[static_cast<std::size_t>(k)];
    for (int a = 0; a < mesh.verticesPerElement(); ++a) {
      const int w = mesh.elementVertex(e, a);
      if (w != v && !fast[static_cast<std::size_t>(w)]) return false;
    }
  }
  return true;
}

/// Makes enclosed L vertices (every neighbour fast) fast, until nothing changes.
void fillEnclosed(const TetMesh& mesh, const VertexElementAdjacency& adjacency, std::vector<char>& fast) {
  for (bool changed = true; changed;) {
    changed = false;
    for (int v = 0; v < mesh.numVertices(); ++v) {
      if (fast[static_cast<std::size_t>(v)] || !enclosed(mesh, adjacency, fast, v)) continue;
      fast[static_cast<std::size_t>(v)] = 1;
      changed = true;
    }
  }
}

/// Connected components of fast vertices (through elements), breadth first: the
/// component of every vertex (-1 for L) and their count.
std::vector<int> fastComponents(const TetMesh& mesh, const VertexElementAdjacency& adjacency,
                                const std::vector<char>& fast, int& numComponents) {
  std::vector<int> component(static_cast<std::size_t>(mesh.numVertices()), -1);
  numComponents = 0;
  std::vector<int> queue;
  for (int seed = 0; seed < mesh.numVertices(); ++seed) {
    if (!fast[static_cast<std::size_t>(seed)] || component[static_cast<std::size_t>(seed)] >= 0) continue;
    queue.assign(1, seed);
    component[static_cast<std::size_t>(seed)] = numComponents;
    for (std::size_t head = 0; head < queue.size(); ++head) {
      const int v = queue[head];
      for (int k = adjacency.offsets[static_cast<std::size_t>(v)];
           k < adjacency.offsets[static_cast<std::size_t>(v) + 1]; ++k) {
        const int e = adjacency.elements[static_cast<std::size_t>(k)];
        for (int a = 0; a < mesh.verticesPerElement(); ++a) {
          const int w = mesh.elementVertex(e, a);
          if (fast[static_cast<std::size_t>(w)] && component[static_cast<std::size_t>(w)] < 0) {
            component[static_cast<std::size_t>(w)] = numComponents;
            queue.push_back(w);
          }
        }
      }
    }
    ++numComponents;
  }
  return component;
}

/// One region per component with a free DOF, its largest element frequency (every element
/// touching it is integrated at least partly at its substep), element count and ratio;
/// L's largest frequency into the proposal.
void collectRegions(const TetMesh& mesh, const FreeDofs& freeDofs, const Eigen::VectorXd& omega,
                    const std::vector<int>& component, int numComponents, int maxRatio, RegionProposal& proposal) {
  std::vector<ProposedRegion> regions(static_cast<std::size_t>(numComponents));
  for (int e = 0; e < mesh.numElements(); ++e) {
    int owner = -1;
    bool allFast = true;
    for (int a = 0; a < mesh.verticesPerElement(); ++a) {
      const int c = component[static_cast<std::size_t>(mesh.elementVertex(e, a))];
      if (c >= 0) owner = c;
      allFast = allFast && c >= 0;
    }
    if (owner < 0) {
      proposal.largeRegionMaxFrequency = std::max(proposal.largeRegionMaxFrequency, omega[e]);
      continue;
    }
    ProposedRegion& r = regions[static_cast<std::size_t>(owner)];
    r.maxFrequency = std::max(r.maxFrequency, omega[e]);
    if (allFast) ++r.numElements;
  }
  for (int v = 0; v < mesh.numVertices(); ++v) {
    const int c = component[static_cast<std::size_t>(v)];
    if (c >= 0) regions[static_cast<std::size_t>(c)].region.vertices.push_back(v);
  }
  for (ProposedRegion& r : regions) {
    bool hasFree = false;
    for (int v : r.region.vertices)
      for (int c = 0; c < 3; ++c) hasFree = hasFree || !freeDofs.isFixed(3 * v + c);
    if (!hasFree) continue;
    const double wanted = std::ceil(r.maxFrequency * proposal.largeTimestep / proposal.targetOmegaH - 1e-12);
    r.region.ratio = static_cast<int>(std::clamp(wanted, 1.0, static_cast<double>(maxRatio)));
    r.region.name = "auto" + std::to_string(proposal.regions.size() + 1);
    proposal.regions.push_back(std::move(r));
  }
}

/// Keeps the maxRegions regions that need the largest ratios (then the largest ones):
/// every region costs its own factor, Z and interface block.
void capRegions(int maxRegions, RegionProposal& proposal) {
  if (static_cast<int>(proposal.regions.size()) <= std::max(maxRegions, 0)) return;
  std::stable_sort(proposal.regions.begin(), proposal.regions.end(),
                   [](const ProposedRegion& a, const ProposedRegion& b) {
                     if (a.region.ratio != b.region.ratio) return a.region.ratio > b.region.ratio;
                     return a.region.vertices.size() > b.region.vertices.size();
                   });
  const auto keep = static_cast<std::ptrdiff_t>(std::max(maxRegions, 0));
  proposal.cappedRegions.assign(std::make_move_iterator(proposal.regions.begin() + keep),
                                std::make_move_iterator(proposal.regions.end()));
  proposal.regions.erase(proposal.regions.begin() + keep, proposal.regions.end());
  for (std::size_t i = 0; i < proposal.regions.size(); ++i)
    proposal.regions[i].region.name = "auto" + std::to_string(i + 1);
}

/// The cost check (options.costCheck): withdraws the regions unless async is estimated
/// cheaper than single-rate at the step their ratios stand for.
void costCheck(const TetMesh& mesh, const FreeDofs& freeDofs, const RegionProposalOptions& options,
               RegionProposal& proposal) {
  if (!options.costCheck || proposal.regions.empty()) return;
  proposal.decidedBy = RegionProposalPath::costCheck;
  proposal.cost = estimateAsyncCost(mesh, freeDofs, proposal.asyncRegions(), options.nonlinear, options.costMargin);
  if (!proposal.cost.asyncCheaper) {
    proposal.costWithdrawnRegions = std::move(proposal.regions);
    proposal.regions.clear();
  }
}

double median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2), values.end());
  return values[values.size() / 2];
}

/// The pre-check (RegionProposalOptions::precheck): whether any element is fast by its material
/// and size alone (elementSizeFrequency() above the target the element criterion uses: the
/// relative threshold times their median, or the absolute target). When none is, the
/// elements the criterion marked are fast by their shape only (flat, slim or cut elements,
/// whose fastest modes are the element's own), and the regions are withdrawn.
void precheckRegions(const TetMesh& mesh, const Eigen::VectorXd& omega, const RegionProposalOptions& options,
                     RegionProposal& proposal) {
  RegionProposalPrecheck& check = proposal.precheck;
  check.evaluated = true;
  const int numElements = mesh.numElements();
  std::vector<double> speed(mesh.materials().size());
  for (std::size_t k = 0; k < speed.size(); ++k) {
    const Material& material = mesh.materials()[k];
    speed[k] = mesh.isHexahedral() ? hexahedronMaxFrequency(detail::unitCube(), material)
                                   : elementMaxFrequency(unitRegularTet(), material);
  }
  std::vector<double> sizeFrequency(static_cast<std::size_t>(numElements));
  double minSpeed = std::numeric_limits<double>::infinity(), maxSpeed = 0.0;
  double minEdge = std::numeric_limits<double>::infinity(), maxEdge = 0.0;
  for (int e = 0; e < numElements; ++e) {
    const double c = speed[static_cast<std::size_t>(mesh.elementMaterialIndex(e))];
    const double edge = mesh.isHexahedral() ? detail::rmsEdgeLength(mesh.hexahedronRestPositions(e))
                                            : rmsEdgeLength(mesh.elementRestPositions(e));
    sizeFrequency[static_cast<std::size_t>(e)] = c / edge;
    minSpeed = std::min(minSpeed, c);
    maxSpeed = std::max(maxSpeed, c);
    minEdge = std::min(minEdge, edge);
    maxEdge = std::max(maxEdge, edge);
    if (omega[e] * proposal.largeTimestep > proposal.targetOmegaH) ++check.markedElements;
  }
  const double typical = median(sizeFrequency);
  const double hL = proposal.largeTimestep;
  check.sizeTarget = options.targetOmegaH > 0.0 ? options.targetOmegaH : options.relativeThreshold * typical * hL;
  double largest = 0.0;
  for (const double w : sizeFrequency) {
    largest = std::max(largest, w);
    if (w * hL > check.sizeTarget) ++check.sizeMarkedElements;
  }
  check.medianSizeFrequency = typical;
  check.maxSizeFrequencyRatio = typical > 0.0 ? largest / typical : 0.0;
  check.waveSpeedSpread = minSpeed > 0.0 ? maxSpeed / minSpeed : 1.0;
  check.sizeSpread = minEdge > 0.0 ? maxEdge / minEdge : 1.0;
  check.shapeOnly = check.sizeMarkedElements == 0;
  if (check.shapeOnly) {
    proposal.precheckWithdrawnRegions = std::move(proposal.regions);
    proposal.regions.clear();
    proposal.decidedBy = RegionProposalPath::precheck;
  }
}

/// The element criterion, the cap, the pre-check when asked (with the modal check) and the
/// cost check.
RegionProposal propose(const TetMesh& mesh, const FreeDofs& freeDofs, const RegionProposalOptions& options,
                       bool precheck) {
  validate(options);
  Stopwatch total;
  total.start();
  const Eigen::VectorXd omega = elementMaxFrequencies(mesh);
  RegionProposal proposal;
  proposal.frequencySeconds = total.stop();
  total.start();
  proposal.largeTimestep = options.largeTimestep;
  proposal.modeOmegaSubstep = options.modeOmegaSubstep;
  proposal.targetOmegaH = targetOmegaH(omega, options);
  const VertexElementAdjacency adjacency = vertexElementAdjacency(mesh);
  std::vector<char> fast = fastVertices(mesh, omega, proposal.largeTimestep, proposal.targetOmegaH, options.growLayers);
  fillEnclosed(mesh, adjacency, fast);
  int numComponents = 0;
  const std::vector<int> component = fastComponents(mesh, adjacency, fast, numComponents);
  collectRegions(mesh, freeDofs, omega, component, numComponents, options.maxRatio, proposal);
  capRegions(options.maxRegions, proposal);
  if (precheck && !proposal.regions.empty()) {
    precheckRegions(mesh, omega, options, proposal);
    if (proposal.decidedBy == RegionProposalPath::precheck) {
      total.stop();
      proposal.decisionSeconds = total.totalSeconds();
      return proposal;
    }
  }
  // Interface sizes, from the partition the proposal defines.
  const RegionPartition partition(mesh, freeDofs, proposal.asyncRegions());
  for (int i = 0; i < partition.numRegions(); ++i) {
    proposal.regions[static_cast<std::size_t>(i)].numInterfaceDofs =
        static_cast<int>(partition.interfaceDofs(i).size());
  }
  costCheck(mesh, freeDofs, options, proposal);
  total.stop();
  proposal.decisionSeconds = total.totalSeconds();
  return proposal;
}

}  // namespace

RegionProposal proposeRegions(const TetMesh& mesh, const FreeDofs& freeDofs, const RegionProposalOptions& options) {
  return propose(mesh, freeDofs, options, false);
}

std::vector<ModalRegion> modalRegions(const std::vector<AsyncRegion>& regions) {
  std::vector<ModalRegion> out;
  out.reserve(regions.size());
  for (const AsyncRegion& r : regions) out.push_back({r.name, r.vertices, r.ratio});
  return out;
}

namespace {
/// Sets each region's ratio from the modes it keeps: every visible mode living in S
/// (mainly in that region) and damped at hL gets omega hS <= options.modeOmegaSubstep,
/// capped at options.maxRatio, when that needs more than the element criterion's ratio
/// (kept in ratioFromElements; modeForRatio names the fastest such mode). Returns whether
/// a ratio changed.
bool ratiosFromModes(const RegionProposalOptions& options, RegionProposal& proposal) {
  bool raised = false;
  const std::vector<ModeInRegions>& modes = proposal.modalReport->modes;
  for (std::size_t k = 0; k < modes.size(); ++k) {
    const ModeInRegions& mode = modes[k];
    if (!mode.livesInFastRegions || mode.omegaLargeStep < modalCriteria::minDampedOmegaLargeStep) continue;
    const auto main = static_cast<std::size_t>(std::max_element(mode.regionShare.begin(), mode.regionShare.end()) -
                                               mode.regionShare.begin());
    ProposedRegion& region = proposal.regions[main];
    const double wanted = std::ceil(mode.omegaLargeStep / options.modeOmegaSubstep - 1e-12);
    const int needed = static_cast<int>(std::clamp(wanted, 1.0, static_cast<double>(options.maxRatio)));
    if (needed > region.region.ratio) {
      if (region.ratioFromElements == 0) region.ratioFromElements = region.region.ratio;
      region.region.ratio = needed;
      region.modeForRatio = static_cast<int>(k);
      raised = true;
    }
  }
  return raised;
}

/// How many modes to ask for next when the highest of `frequencies` (ascending, k of them)
/// is still below the Nyquist frequency: the count N(omega) = k (omega / omega_k)^p of a
/// power law through the computed spectrum (p from modes k/2 and k) at the Nyquist
/// frequency, plus a fifth, and at least 2k. One more Lanczos run then usually covers every
/// visible mode, where doubling took up to three (each a basis of 2k + 1 solves).
int nextModalCount(const Eigen::VectorXd& frequencies, double nyquist) {
  const auto k = static_cast<int>(frequencies.size());
  int next = 2 * k;
  const double low = frequencies[k / 2 - 1], high = frequencies[k - 1];
  if (k >= 4 && low > 0.0 && high > low) {
    const double power = std::log(static_cast<double>(k) / (k / 2)) / std::log(high / low);
    const double predicted = k * std::pow(nyquist / high, power);
    if (std::isfinite(predicted)) next = std::max(next, static_cast<int>(std::ceil(1.2 * predicted)));
  }
  return next;
}

/// The lowest modes of (stiffness, mass) on the free DOFs: options.modalCount, raised by
/// nextModalCount() while the highest is still below the Nyquist frequency (visible modes beyond the
/// computed ones could live in S), up to maxModalCount; one factorization of K - sigma M
/// for every count (LowestModesSolver), Ritz values to options.modalTolerance.
ModalResult modesUpToNyquist(const FreeDofs& freeDofs, const RegionProposalOptions& options,
                             const Eigen::SparseMatrix<double>& stiffness, const Eigen::SparseMatrix<double>& mass,
                             RegionProposal& proposal) {
  Stopwatch watch;
  const double nyquist = modalCriteria::nyquistPerFrameRate * options.frameRate;
  const int largestCount = std::min(options.maxModalCount, freeDofs.numFree() - 1);
  ModalOptions modal;
  modal.tolerance = options.modalTolerance;
  int count = std::min(options.modalCount, largestCount);
  modal.count = count;
  const LowestModesSolver solver(stiffness, mass, freeDofs, modal);
  ModalResult modes = solver.compute(count);
  while (modes.frequencies[modes.frequencies.size() - 1] < nyquist && count < largestCount) {
    count = std::min(nextModalCount(modes.frequencies, nyquist), largestCount);
    modes = solver.compute(count);
  }
  modes.factorSeconds = solver.factorSeconds();
  proposal.modalFactorizations = 1;
  proposal.modalSolves = solver.operatorApplications();
  proposal.modalFactorSeconds = solver.factorSeconds();
  proposal.modalSeconds = watch.stop();
  return modes;
}

/// The modal check of the element criterion's regions (options.modalCheck): ratios from
/// the modes they keep (then priced again by the cost check), withdrawn when no visible
/// mode lives in them.
void validateModalCheck(const RegionProposalOptions& options) {
  if (!(options.frameRate > 0.0) || !std::isfinite(options.frameRate)) {
    throw ValidationError("proposed regions: the frame rate of the modal check must be positive");
  }
  if (options.modalCount < 1 || options.maxModalCount < options.modalCount) {
    throw ValidationError("proposed regions: need 1 <= modalCount <= maxModalCount for the modal check");
  }
  if (!(options.modeOmegaSubstep > 0.0) || !std::isfinite(options.modeOmegaSubstep)) {
    throw ValidationError("proposed regions: modeOmegaSubstep must be positive");
  }
  if (!(options.modalTolerance > 0.0) || !std::isfinite(options.modalTolerance)) {
    throw ValidationError("proposed regions: modalTolerance must be positive");
  }
}

void checkModes(const TetMesh& mesh, const FreeDofs& freeDofs, const RegionProposalOptions& options,
                const Eigen::SparseMatrix<double>& stiffness, const Eigen::SparseMatrix<double>& mass,
                RegionProposal& proposal) {
  if (proposal.regions.empty()) return;
  const ModalResult modes = modesUpToNyquist(freeDofs, options, stiffness, mass, proposal);
  proposal.decidedBy = RegionProposalPath::modalCheck;
  const auto report = [&] {
    return analyseRegionModes(modes, mass, modalRegions(proposal.asyncRegions()), options.largeTimestep,
                              options.frameRate);
  };
  proposal.modalReport = report();
  if (ratiosFromModes(options, proposal)) {
    proposal.modalReport = report();
    costCheck(mesh, freeDofs, options, proposal);
  }
  proposal.decidedBy = RegionProposalPath::modalCheck;  // also when its ratios sent the regions to the cost check again
  if (proposal.modalReport->verdict == ModalVerdict::noVisibleModeInFast) {
    proposal.withdrawnRegions = std::move(proposal.regions);
    proposal.regions.clear();
  }
}
}  // namespace

RegionProposal proposeRegions(const TetMesh& mesh, const FreeDofs& freeDofs, const RegionProposalOptions& options,
                              const Eigen::SparseMatrix<double>& stiffness, const Eigen::SparseMatrix<double>& mass) {
  Stopwatch total;
  total.start();
  RegionProposal proposal = propose(mesh, freeDofs, options, options.modalCheck && options.precheck);
  if (options.modalCheck) {
    validateModalCheck(options);
    checkModes(mesh, freeDofs, options, stiffness, mass, proposal);
  }
  total.stop();
  proposal.decisionSeconds = total.totalSeconds();
  return proposal;
}

RegionProposal proposeRegions(const TetMesh& mesh, const FreeDofs& freeDofs, const RegionProposalOptions& options,
                              MassType massType) {
  Stopwatch total;
  total.start();
  RegionProposal proposal = propose(mesh, freeDofs, options, options.modalCheck && options.precheck);
  if (options.modalCheck) {
    validateModalCheck(options);
    if (!proposal.regions.empty()) {
      // K (the linear one: the corotational rest tangent) and M, only for a modal check that runs.
      const VibrationMatrices matrices = vibrationMatrices(mesh, massType);
      checkModes(mesh, freeDofs, options, matrices.stiffness, matrices.mass, proposal);
    }
  }
  total.stop();
  proposal.decisionSeconds = total.totalSeconds();
  return proposal;
}

std::string ratioReason(const RegionProposal& proposal, const ProposedRegion& region) {
  char text[300];
  const int m = region.region.ratio;
  if (region.modeForRatio >= 0 && proposal.modalReport) {
    const ModeInRegions& mode = proposal.modalReport->modes[static_cast<std::size_t>(region.modeForRatio)];
    std::snprintf(text, sizeof text,
                  "m = %d for mode %d (%.3g Hz, omega*hL %.3g), the fastest visible mode living in it and damped at "
                  "hL: omega*hS %.3g <= %g (the element criterion alone gives m = %d)",
                  m, region.modeForRatio + 1, mode.hertz, mode.omegaLargeStep, mode.omegaLargeStep / m,
                  proposal.modeOmegaSubstep, region.ratioFromElements);
  } else {
    std::snprintf(text, sizeof text, "m = %d from the element criterion: max omega_e*hL %.3g against the target %.3g",
                  m, region.maxFrequency * proposal.largeTimestep, proposal.targetOmegaH);
  }
  return text;
}

namespace {
std::string regionProposalDecision(const RegionProposal& proposal) {
  const std::string prefix = "\"auto\": ";
  if (!proposal.regions.empty()) {
    std::string line = prefix + std::to_string(proposal.regions.size()) + " region(s) kept:";
    for (const ProposedRegion& r : proposal.regions) {
      line += " " + r.region.name + " (" + std::to_string(r.region.vertices.size()) + " vertices, " +
              ratioReason(proposal, r) + ")";
    }
    return line;
  }
  if (!proposal.precheckWithdrawnRegions.empty()) {
    const RegionProposalPrecheck& c = proposal.precheck;
    char line[600];
    std::snprintf(line, sizeof line,
                  "no fast region kept, single-rate at hL: the pre-check found no light or stiff part: wave speeds "
                  "within %.3gx and element sizes within %.3gx leave every element's frequency at its material and "
                  "size (a regular tet's) within %.3gx of their median (the limit: %.3gx), so the %d element(s) above "
                  "the target omega*hL = %.3g are fast by their shape alone; %zu region(s) withdrawn, no modal solve",
                  c.waveSpeedSpread, c.sizeSpread, c.maxSizeFrequencyRatio,
                  c.medianSizeFrequency > 0.0 ? c.sizeTarget / (proposal.largeTimestep * c.medianSizeFrequency) : 0.0,
                  c.markedElements, proposal.targetOmegaH, proposal.precheckWithdrawnRegions.size());
    return prefix + line;
  }
  if (!proposal.withdrawnRegions.empty()) {
    return prefix + "no fast region kept, single-rate at hL: the modal check withdrew " +
           std::to_string(proposal.withdrawnRegions.size()) +
           " region(s): " + (proposal.modalReport ? proposal.modalReport->verdictText() : std::string());
  }
  if (!proposal.costWithdrawnRegions.empty()) {
    return prefix + "no fast region kept, single-rate at hL: the cost check withdrew " +
           std::to_string(proposal.costWithdrawnRegions.size()) + " region(s): " + proposal.cost.decision;
  }
  char line[200];
  std::snprintf(line, sizeof line,
                "no fast region needed, single-rate at hL: every element meets the target omega*hL = %.3g",
                proposal.targetOmegaH);
  return prefix + line;
}
}  // namespace

std::string regionProposalSummary(const RegionProposal& proposal) {
  char decided[200];
  if (proposal.modalFactorizations > 0) {
    std::snprintf(decided, sizeof decided,
                  " (decided in %.3g ms by the %s; its modal solve %.3g ms: %d factorization (%.3g ms) and %d solves)",
                  1e3 * proposal.decisionSeconds, toString(proposal.decidedBy), 1e3 * proposal.modalSeconds,
                  proposal.modalFactorizations, 1e3 * proposal.modalFactorSeconds, proposal.modalSolves);
  } else {
    std::snprintf(decided, sizeof decided, " (decided in %.3g ms by the %s)", 1e3 * proposal.decisionSeconds,
                  toString(proposal.decidedBy));
  }
  return regionProposalDecision(proposal) + decided;
}

}  // namespace asyncfem
