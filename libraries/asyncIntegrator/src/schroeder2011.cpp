// SPDX-License-Identifier: BSD-3-Clause
// The asynchronous scheme of Schroeder, Kwatra, Zheng & Fedkiw 2011. Equation numbers
// (S1)-(S7) refer to docs/asynchronous-integrator.md, section "Schroeder et al. 2011".
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/SparseCore>
#include <algorithm>
#include <asyncfem/asyncIntegrator/schroeder2011.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/integrator/stableTimestep.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>
#include <string>

#include "detail/elementTangents.hpp"
#include "detail/fastRegion.hpp"
#include "detail/meshElements.hpp"
#include "detail/multirateSupport.hpp"
#include "detail/sparseBlocks.hpp"

namespace asyncfem {

namespace {

using SparseMatrix = Eigen::SparseMatrix<double>;
using detail::gather;
using detail::updateBlock;

constexpr const char* kName = "schroeder2011";

/// An element with vertices in S_i and in L: where its 12 (tetrahedron) or 24 (hexahedron)
/// DOFs sit among the region's interface DOFs I_i (-1 for S DOFs and fixed DOFs).
struct InterfaceElement {
  int element = 0;
  std::vector<int> interfaceIndex;
};

/// (S7): the largest h with h^2 omega^2 <= 4 + 2 h c, c = alpha + beta omega^2, the
/// stability bound of the semi-implicit update (S3) for an undamped-elastic mode omega
/// with implicit damping c. Decreasing in omega, so omega_max gives the binding limit.
double semiImplicitLimit(double omega, double alpha, double beta) {
  if (!(omega > 0.0)) return std::numeric_limits<double>::infinity();
  const double c = alpha + (beta * omega * omega);
  return (c + std::sqrt((c * c) + (4.0 * omega * omega))) / (omega * omega);
}

}  // namespace

// ---------------------------------------------------------------------------------------
// The force distributing projection (S5)

RigidImpulseProjection::RigidImpulseProjection(const Eigen::VectorXd& positions, const Eigen::VectorXd& lumpedMass,
                                               std::vector<int> dofs)
    : dofs_(std::move(dofs)) {
  const Eigen::Index count = static_cast<Eigen::Index>(dofs_.size());
  modes_.setZero(count, 6);
  weightedModes_.setZero(count, 6);
  inverseInertia_.setZero(6, 6);
  if (count == 0) return;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  double totalMass = 0.0;
  for (const int dof : dofs_) {
    const int vertex = dof / 3;
    if (!(lumpedMass[dof] > 0.0)) {
      throw NumericalError(std::string(kName) + ": non-positive lumped mass at DOF " + std::to_string(dof));
    }
    centroid += lumpedMass[dof] * positions.segment<3>(3 * vertex);
    totalMass += lumpedMass[dof];
  }
  centroid /= totalMass;
  // The rotations are scaled by the set's rms radius so that all six columns have the
  // same units (the projection depends only on their span).
  double radius2 = 0.0;
  for (const int dof : dofs_) radius2 += (positions.segment<3>(3 * (dof / 3)) - centroid).squaredNorm();
  const double radius = std::sqrt(radius2 / static_cast<double>(count));
  const double scale = radius > 0.0 ? 1.0 / radius : 0.0;
  for (Eigen::Index k = 0; k < count; ++k) {
    const int dof = dofs_[static_cast<std::size_t>(k)];
    const int component = dof % 3;
    const Eigen::Vector3d r = positions.segment<3>(3 * (dof / 3)) - centroid;
    modes_(k, component) = 1.0;
    for (int axis = 0; axis < 3; ++axis) {
      const Eigen::Vector3d rotation = Eigen::Vector3d::Unit(axis).cross(r);
      modes_(k, 3 + axis) = scale * rotation[component];
    }
    weightedModes_.row(k) = lumpedMass[dof] * modes_.row(k);
  }
  // (Phi^T W Phi)^+: modes the set cannot carry (eigenvalue ~ 0) are dropped.
  const Eigen::MatrixXd inertia = modes_.transpose() * weightedModes_;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(inertia);
  const Eigen::VectorXd& values = eigen.eigenvalues();
  const double cutoff = 1e-12 * std::max(values.cwiseAbs().maxCoeff(), 1e-300);
  Eigen::VectorXd inverse = Eigen::VectorXd::Zero(values.size());
  for (Eigen::Index k = 0; k < values.size(); ++k)
    if (values[k] > cutoff) inverse[k] = 1.0 / values[k];
  inverseInertia_ = eigen.eigenvectors() * inverse.asDiagonal() * eigen.eigenvectors().transpose();
}

Eigen::VectorXd RigidImpulseProjection::apply(const Eigen::VectorXd& impulse, double rigidity) const {
  Eigen::VectorXd out = Eigen::VectorXd::Zero(impulse.size());
  if (dofs_.empty()) return out;
  const Eigen::VectorXd local = gather(impulse, dofs_);
  const Eigen::VectorXd projected = weightedModes_ * (inverseInertia_ * (modes_.transpose() * local));
  const Eigen::VectorXd filtered = ((1.0 - rigidity) * local) + (rigidity * projected);
  for (std::size_t k = 0; k < dofs_.size(); ++k) out[dofs_[k]] = filtered[static_cast<Eigen::Index>(k)];
  return out;
}

// ---------------------------------------------------------------------------------------
// The integrator

struct Schroeder2011::Impl {
  bool linear = true;
  bool built = false;
  std::optional<detail::ElementTangents> tangents;  // where each interface element's K_e comes from
  bool lumpedConsistentMass = false;                // the system's consistent M was replaced by its row sums
  SparseMatrix stiffness;                           // K(u_0), full
  Eigen::VectorXd internalForce;
  Eigen::VectorXd lumpedMass;  // row sums of M (3n)
  SubmatrixExtractor freeMass, freeStiffness;
  SparseMatrix Mff, Kff;
  bool cutFree = false;
  std::vector<int> freeRegion;  // region of every free DOF (-1: L)
  SparseMatrix compound;
  std::unique_ptr<SparseSolver> compoundSolver;
  bool compoundAnalyzed = false;
  std::vector<detail::FastRegion> regions;
  std::vector<std::vector<InterfaceElement>> interfaceElements;
  std::vector<SparseMatrix> interfaceStiffness;  // K_if,i^{II}: interface elements' tangent on I_i x I_i
  std::vector<double> maxFrequency;              // omega_max of (K^{SS}, M^{SS}) per region
  // Per-step state of the regions after their substeps r = 1..m-1.
  std::vector<Eigen::VectorXd> lastU, lastV;
};

Schroeder2011::Schroeder2011(const TetMesh& mesh, DynamicSystem system, double largeTimestep,
                             std::vector<AsyncRegion> regions, Schroeder2011Options options)
    : Schroeder2011(withMesh(kName, mesh, std::move(system)), largeTimestep, std::move(regions), options) {}

Schroeder2011::Schroeder2011(DynamicSystem system, double largeTimestep, std::vector<AsyncRegion> regions,
                             Schroeder2011Options options)
    : PartitionedIntegrator(kName, std::move(system), largeTimestep, std::move(regions), false),
      options_(options),
      impl_(std::make_unique<Impl>()) {
  if (!(options_.rigidity >= 0.0 && options_.rigidity <= 1.0)) {
    throw ValidationError(std::string(kName) + ": rigidity must lie in [0, 1] (got " +
                          std::to_string(options_.rigidity) + ")");
  }
  Impl& d = *impl_;
  const TetMesh& mesh = *system_.mesh;
  // SKZF11 advances particles with their own masses: a consistent M is lumped to its row
  // sums (S1). With the consistent M's cross blocks M^{SL}, the explicit substeps and the
  // frame-rate L step exchange momentum through M^{LS} (v^S_{m-1} - v^S_0), a lagged
  // coupling that gains energy without bound (seen on the stiff-end bar at every ratio).
  d.lumpedMass = system_.mass * Eigen::VectorXd::Ones(system_.numDofs());
  bool diagonal = true;
  for (int c = 0; c < system_.mass.outerSize() && diagonal; ++c)
    for (SparseMatrix::InnerIterator it(system_.mass, c); it; ++it)
      if (it.row() != c && it.value() != 0.0) {
        diagonal = false;
        break;
      }
  if (!diagonal) {
    system_.mass = SparseMatrix(d.lumpedMass.asDiagonal());
    system_.mass.makeCompressed();
    d.lumpedConsistentMass = true;
  }
  d.linear = system_.forceModel->isLinear();
  d.stiffness = system_.forceModel->createStiffnessMatrix();
  system_.forceModel->tangentStiffness(Eigen::VectorXd::Zero(system_.numDofs()), d.stiffness);
  d.stiffness.makeCompressed();
  detail::setUpCompoundBlocks(system_, partition_, options_.regionSolver, options_.compoundSolver, d);
  const int numRegions = partition_.numRegions();
  for (int i = 0; i < numRegions; ++i) {
    detail::FastRegion& region = d.regions[static_cast<std::size_t>(i)];
    region.updateStiffnessBlocks(d.stiffness);
  }
  d.lastU.resize(static_cast<std::size_t>(numRegions));
  d.lastV.resize(static_cast<std::size_t>(numRegions));

  collectInterfaceElements();
  d.tangents.emplace(mesh, *system_.forceModel, kName);
  checkInterfaceStiffness();

  // The outer layer's omega_max (S7), from the tangent at rest.
  d.maxFrequency.assign(static_cast<std::size_t>(numRegions), 0.0);
  for (int i = 0; i < numRegions; ++i) {
    const detail::FastRegion& region = d.regions[static_cast<std::size_t>(i)];
    d.maxFrequency[static_cast<std::size_t>(i)] = estimateMaxFrequency(region.Kss, region.Mss);
  }
  checkSubsteps(timestep());
  if (!system_.damped()) stats_.skipped.push_back("damping terms (alpha = beta = 0)");
  if (d.linear) stats_.skipped.push_back("per-step refactorization (linear forces: factored once)");
}

Schroeder2011::~Schroeder2011() = default;

// The interface elements of every region, with their I-local DOF indices.
void Schroeder2011::collectInterfaceElements() {
  Impl& d = *impl_;
  const TetMesh& mesh = *system_.mesh;
  const int numRegions = partition_.numRegions();
  d.interfaceElements.resize(static_cast<std::size_t>(numRegions));
  d.interfaceStiffness.resize(static_cast<std::size_t>(numRegions));
  std::vector<std::vector<int>> interfaceIndex(static_cast<std::size_t>(numRegions));
  for (int i = 0; i < numRegions; ++i) {
    std::vector<int>& index = interfaceIndex[static_cast<std::size_t>(i)];
    index.assign(static_cast<std::size_t>(mesh.numDofs()), -1);
    const std::vector<int>& iface = partition_.interfaceDofs(i);
    for (std::size_t k = 0; k < iface.size(); ++k) index[static_cast<std::size_t>(iface[k])] = static_cast<int>(k);
  }
  for (const int e : partition_.interfaceElements()) {
    int fast = -1;
    for (int a = 0; a < mesh.verticesPerElement(); ++a)
      fast = std::max(fast, partition_.vertexRegion()[static_cast<std::size_t>(mesh.elementVertex(e, a))]);
    if (fast < 0) continue;
    InterfaceElement element;
    element.element = e;
    for (int p = 0; p < detail::elementDofs(mesh); ++p)
      element.interfaceIndex.push_back(
          interfaceIndex[static_cast<std::size_t>(fast)][static_cast<std::size_t>(detail::elementDof(mesh, e, p))]);
    d.interfaceElements[static_cast<std::size_t>(fast)].push_back(element);
  }
}

// The interface elements' K^{SI} block must be the model's (S rows of K come from
// elements touching S, all of them outer-layer or interface elements): checks that
// the element tangents (or, for a matrix-built linear model, the mesh's linear FEM
// elements) are the model's. 1e-10 relative: the same element matrices summed in
// another order differ by ~1e-15; another material differs by far more.
void Schroeder2011::checkInterfaceStiffness() const {
  const Impl& d = *impl_;
  const TetMesh& mesh = *system_.mesh;
  const int numRegions = partition_.numRegions();
  for (int i = 0; i < numRegions; ++i) {
    const std::vector<int>& s = partition_.regionDofs(i);
    std::vector<int> sIndex(static_cast<std::size_t>(mesh.numDofs()), -1);
    for (std::size_t k = 0; k < s.size(); ++k) sIndex[static_cast<std::size_t>(s[k])] = static_cast<int>(k);
    std::vector<Eigen::Triplet<double>> triplets;
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(mesh.numDofs());
    Eigen::MatrixXd tangent;
    for (const InterfaceElement& element : d.interfaceElements[static_cast<std::size_t>(i)]) {
      interfaceTangent(zero, element.element, tangent);
      for (int p = 0; p < tangent.rows(); ++p) {
        const int row = sIndex[static_cast<std::size_t>(detail::elementDof(mesh, element.element, p))];
        if (row < 0) continue;
        for (int q = 0; q < tangent.cols(); ++q) {
          const int column = element.interfaceIndex[static_cast<std::size_t>(q)];
          if (column >= 0) triplets.emplace_back(row, column, tangent(p, q));
        }
      }
    }
    const detail::FastRegion& region = d.regions[static_cast<std::size_t>(i)];
    SparseMatrix fromElements(region.Ksi.rows(), region.Ksi.cols());
    fromElements.setFromTriplets(triplets.begin(), triplets.end());
    const double scale = std::max(detail::largestMagnitude(region.Ksi), 1e-300);
    const SparseMatrix difference = fromElements - region.Ksi;
    const double relative = detail::largestMagnitude(difference) / scale;
    if (!(relative <= 1e-10)) {
      throw ValidationError(std::string(kName) + ": fast region '" + partition_.region(i).name +
                            "': the interface elements' stiffness differs from the force model's K on the interface "
                            "(relative difference " +
                            std::to_string(relative) +
                            "); a force model built from a matrix must be the mesh's linear FEM stiffness");
    }
  }
}

void Schroeder2011::interfaceTangent(const Eigen::VectorXd& u, int element, Eigen::MatrixXd& tangent) const {
  impl_->tangents->tangent(u, element, tangent);
}

double Schroeder2011::outerLayerMaxFrequency(int region) const {
  return impl_->maxFrequency.at(static_cast<std::size_t>(region));
}

double Schroeder2011::largestStableSubstep(int region) const {
  return semiImplicitLimit(outerLayerMaxFrequency(region), system_.rayleighMass, system_.rayleighStiffness);
}

double Schroeder2011::stableTimestepEstimate() const {
  double limit = std::numeric_limits<double>::infinity();
  for (int i = 0; i < partition_.numRegions(); ++i) {
    if (partition_.ratio(i) > 1) limit = std::min(limit, partition_.ratio(i) * largestStableSubstep(i));
  }
  return limit;
}

void Schroeder2011::checkSubsteps(double largeTimestep) const {
  if (options_.force) return;
  for (int i = 0; i < partition_.numRegions(); ++i) {
    const int m = partition_.ratio(i);
    if (m == 1) continue;  // no explicit substep: the only step is the implicit solve (S6)
    const double hS = largeTimestep / m;
    const double limit = largestStableSubstep(i);
    if (hS <= limit) continue;
    std::ostringstream message;
    message.precision(6);
    message << kName << ": fast region S_" << (i + 1) << " '" << partition_.region(i).name
            << "': substep hS = hL / m = " << largeTimestep << " / " << m << " = " << hS << " s exceeds " << limit
            << " s, the largest stable substep of its semi-implicit outer-layer update (explicit elastic forces, "
               "implicit damping; omega_max = "
            << outerLayerMaxFrequency(i) << " rad/s); raise its ratio to at least "
            << static_cast<long long>(std::ceil(largeTimestep / limit))
            << " or lower the large timestep, or set the option force to run anyway (scene key "
               "integrator.options.force: true)";
    throw TimestepError(message.str());
  }
}

void Schroeder2011::setTimestep(double timestep) {
  if (impl_) checkSubsteps(timestep);
  Integrator::setTimestep(timestep);
  if (impl_) impl_->built = false;
}

// The coupled matrix of (S6) on the free DOFs, the substep matrices of (S3) and the
// interface elements' K_if^{II} at the current tangent.
// M and K of the free DOFs, each entry weighted with the steps of its row and column (S6).
void Schroeder2011::appendSteppedBlocks(std::vector<Eigen::Triplet<double>>& triplets) const {
  const Impl& d = *impl_;
  const double hL = timestep();
  const double alpha = system_.rayleighMass, beta = system_.rayleighStiffness;
  auto stepOf = [&](int region) { return region < 0 ? hL : hL / partition_.ratio(region); };
  // Mass: (1 + h alpha) with h the row's step. Stiffness: rows of S (hS h_col + hS beta)
  // with h_col = hS on S columns and hL on L columns; rows of L (hS^2 + hS beta) on
  // S columns and (hL^2 + hL beta) on L columns, corrected on I x I below.
  for (int c = 0; c < d.Mff.outerSize(); ++c) {
    const int columnRegion = d.freeRegion[static_cast<std::size_t>(c)];
    for (SparseMatrix::InnerIterator it(d.Mff, c); it; ++it) {
      const double h = stepOf(d.freeRegion[static_cast<std::size_t>(it.row())]);
      triplets.emplace_back(static_cast<int>(it.row()), c, (1.0 + (h * alpha)) * it.value());
    }
    for (SparseMatrix::InnerIterator it(d.Kff, c); it; ++it) {
      const int rowRegion = d.freeRegion[static_cast<std::size_t>(it.row())];
      double weight = 0.0;
      if (rowRegion >= 0) {
        const double hS = stepOf(rowRegion);
        weight = (hS * stepOf(columnRegion)) + (hS * beta);
      } else if (columnRegion >= 0) {
        const double hS = stepOf(columnRegion);
        weight = (hS * hS) + (hS * beta);
      } else {
        weight = (hL * hL) + (hL * beta);
      }
      triplets.emplace_back(static_cast<int>(it.row()), c, weight * it.value());
    }
  }
}

void Schroeder2011::rebuild() {
  Impl& d = *impl_;
  const double hL = timestep();
  const double alpha = system_.rayleighMass, beta = system_.rayleighStiffness;
  Stopwatch assembly, factor;
  assembly.start();
  updateBlock(d.freeStiffness, d.stiffness, d.Kff, d.cutFree);
  d.cutFree = true;
  const std::vector<int>& fullToFree = system_.freeDofs.fullToFree();
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(static_cast<std::size_t>(d.Mff.nonZeros() + d.Kff.nonZeros()));
  appendSteppedBlocks(triplets);
  const Eigen::VectorXd& u0 = displacement_;
  for (int i = 0; i < partition_.numRegions(); ++i) {
    detail::FastRegion& region = d.regions[static_cast<std::size_t>(i)];
    region.smallStep = hL / region.ratio;
    const double hS = region.smallStep;
    region.updateStiffnessBlocks(d.stiffness);
    // (S3): M^{SS} + hS D^{SS}, damping implicit, elastic forces explicit.
    detail::combineInto(1.0 + (hS * alpha), region.Mss, hS * beta, region.Kss, region.systemMatrix);
    region.systemMatrix.makeCompressed();
    // K_if^{II}, and the interface elements' weight on L's rows: (hS - hL)(hL + beta).
    const std::vector<int>& iface = partition_.interfaceDofs(i);
    std::vector<Eigen::Triplet<double>> local;
    const double correction = (hS - hL) * (hL + beta);
    Eigen::MatrixXd tangent;
    for (const InterfaceElement& element : d.interfaceElements[static_cast<std::size_t>(i)]) {
      interfaceTangent(u0, element.element, tangent);
      for (int p = 0; p < tangent.rows(); ++p) {
        const int row = element.interfaceIndex[static_cast<std::size_t>(p)];
        if (row < 0) continue;
        for (int q = 0; q < tangent.cols(); ++q) {
          const int column = element.interfaceIndex[static_cast<std::size_t>(q)];
          if (column < 0) continue;
          local.emplace_back(row, column, tangent(p, q));
          triplets.emplace_back(fullToFree[static_cast<std::size_t>(iface[static_cast<std::size_t>(row)])],
                                fullToFree[static_cast<std::size_t>(iface[static_cast<std::size_t>(column)])],
                                correction * tangent(p, q));
        }
      }
    }
    SparseMatrix& kif = d.interfaceStiffness[static_cast<std::size_t>(i)];
    kif.resize(static_cast<Eigen::Index>(iface.size()), static_cast<Eigen::Index>(iface.size()));
    kif.setFromTriplets(local.begin(), local.end());
  }
  d.compound.resize(d.Mff.rows(), d.Mff.cols());
  d.compound.setFromTriplets(triplets.begin(), triplets.end());
  d.compound.makeCompressed();
  stats_.assemblySeconds += assembly.stop();

  factor.start();
  detail::factorizeCounted(*d.compoundSolver, d.compound, d.compoundAnalyzed, stats_);
  for (detail::FastRegion& region : d.regions) {
    if (region.ratio > 1) detail::factorizeCounted(*region.solver, region.systemMatrix, region.analyzed, stats_);
  }
  stats_.factorizationSeconds += factor.stop();
}

// (S3): substeps r = 1..m-1 of region i with L left behind (moving with v^L_0); the
// state after them into lastU, lastV, and the impulse of the region's elements on its
// interface DOFs added to boundaryImpulse (full, 3n).
void Schroeder2011::substeps(int i, double t0, Eigen::VectorXd& boundaryImpulse) {
  Impl& d = *impl_;
  detail::FastRegion& region = d.regions[static_cast<std::size_t>(i)];
  const Eigen::VectorXd& u0 = displacement_;
  const Eigen::VectorXd& v0 = velocity_;
  const double alpha = system_.rayleighMass, beta = system_.rayleighStiffness;
  const double hS = region.smallStep;
  const int m = region.ratio;
  const std::vector<int>& s = partition_.regionDofs(i);
  const std::vector<int>& iface = partition_.interfaceDofs(i);
  const SparseMatrix& kif = d.interfaceStiffness[static_cast<std::size_t>(i)];
  const Eigen::VectorXd uS0 = gather(u0, s);
  Eigen::VectorXd& uS = d.lastU[static_cast<std::size_t>(i)];
  Eigen::VectorXd& vS = d.lastV[static_cast<std::size_t>(i)];
  uS = uS0;
  vS = gather(v0, s);
  if (m == 1) return;
  const Eigen::VectorXd vI0 = gather(v0, iface);
  const Eigen::VectorXd fintS = gather(d.internalForce, s);
  // Terms of L's kinematic motion u^I_{r-1} - u^I_0 = (r - 1) hS v^I_0 and of v^I_0.
  const Eigen::VectorXd stiffI = region.Ksi * vI0;
  const Eigen::VectorXd massI = region.Msi * vI0;
  const Eigen::VectorXd ifaceStiffI = kif * vI0;
  Eigen::VectorXd impulseI = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(iface.size()));
  Eigen::VectorXd externalForce, rhs, newV, displacementChange;
  for (int r = 1; r < m; ++r) {
    evaluateExternalForce(t0 + (r * hS), externalForce);
    const double lag = (r - 1) * hS;
    displacementChange = uS - uS0;
    rhs = gather(externalForce, s) - fintS - (region.Kss * displacementChange) - (lag * stiffI);
    if (system_.damped()) {
      rhs -= alpha * ((region.Mss * vS) + massI);
      rhs -= beta * ((region.Kss * vS) + stiffI);
    }
    newV = vS + region.solver->solve(hS * rhs);
    // The reaction on the interface DOFs: the same elements' elastic force at the
    // substep's start and their (implicit) damping force.
    impulseI -= hS * ((region.Kis * displacementChange) + (lag * ifaceStiffI));
    if (beta != 0.0) impulseI -= (hS * beta) * ((region.Kis * newV) + ifaceStiffI);
    vS = newV;
    uS += hS * vS;
  }
  for (std::size_t k = 0; k < iface.size(); ++k) boundaryImpulse[iface[k]] += impulseI[static_cast<Eigen::Index>(k)];
}

// (S6)'s right-hand side on the free DOFs.
Eigen::VectorXd Schroeder2011::coupledRightHandSide(double t1, const Eigen::VectorXd& filteredImpulse) {
  Impl& d = *impl_;
  const Eigen::VectorXd& u0 = displacement_;
  const Eigen::VectorXd& v0 = velocity_;
  const double hL = timestep();
  const double alpha = system_.rayleighMass, beta = system_.rayleighStiffness;
  // Full vectors: z the velocities at the last substep's start, w the displacement change
  // the elastic forces see before the unknowns, q the stiffness products of L's rows, d
  // S's velocity change over the substeps.
  Eigen::VectorXd z = v0, w = hL * v0, q = (hL * (hL + beta)) * v0, change = Eigen::VectorXd::Zero(v0.size());
  for (int i = 0; i < partition_.numRegions(); ++i) {
    const std::vector<int>& s = partition_.regionDofs(i);
    const double hS = d.regions[static_cast<std::size_t>(i)].smallStep;
    const Eigen::VectorXd& uS = d.lastU[static_cast<std::size_t>(i)];
    const Eigen::VectorXd& vS = d.lastV[static_cast<std::size_t>(i)];
    for (std::size_t k = 0; k < s.size(); ++k) {
      const int dof = s[k];
      const Eigen::Index kk = static_cast<Eigen::Index>(k);
      z[dof] = vS[kk];
      w[dof] = uS[kk] + (hS * vS[kk]) - u0[dof];
      q[dof] = hS * (w[dof] + (beta * z[dof]));
      change[dof] = vS[kk] - v0[dof];
    }
  }
  Eigen::VectorXd externalForce;
  evaluateExternalForce(t1, externalForce);
  const Eigen::VectorXd stiffW = d.stiffness * w;
  const Eigen::VectorXd stiffQ = d.stiffness * q;
  const Eigen::VectorXd massChange = system_.mass * change;
  Eigen::VectorXd stiffZ, massZ;
  if (system_.damped()) {
    stiffZ = d.stiffness * z;
    massZ = system_.mass * z;
  }
  // The interface elements over hS instead of hL on L's rows: -(hS - hL)(hL + beta) K_if v^I_0.
  Eigen::VectorXd interfaceTerm = Eigen::VectorXd::Zero(v0.size());
  for (int i = 0; i < partition_.numRegions(); ++i) {
    const std::vector<int>& iface = partition_.interfaceDofs(i);
    const double hS = d.regions[static_cast<std::size_t>(i)].smallStep;
    const Eigen::VectorXd product = d.interfaceStiffness[static_cast<std::size_t>(i)] * gather(v0, iface);
    for (std::size_t k = 0; k < iface.size(); ++k)
      interfaceTerm[iface[k]] += (hS - hL) * (hL + beta) * product[static_cast<Eigen::Index>(k)];
  }
  const std::vector<int>& free = system_.freeDofs.freeToFull();
  Eigen::VectorXd rhs(static_cast<Eigen::Index>(free.size()));
  for (std::size_t k = 0; k < free.size(); ++k) {
    const int dof = free[k];
    const int region = d.freeRegion[k];
    double massDamping = 0.0, stiffDamping = 0.0;
    if (system_.damped()) {
      massDamping = alpha * massZ[dof];
      stiffDamping = beta * stiffZ[dof];
    }
    double value = 0.0;
    if (region >= 0) {
      const double hS = d.regions[static_cast<std::size_t>(region)].smallStep;
      value = hS * (externalForce[dof] - d.internalForce[dof] - stiffW[dof] - massDamping - stiffDamping);
    } else {
      value = (hL * (externalForce[dof] - d.internalForce[dof] - massDamping)) - stiffQ[dof] - interfaceTerm[dof] +
              filteredImpulse[dof] - massChange[dof];
    }
    rhs[static_cast<Eigen::Index>(k)] = value;
  }
  return rhs;
}

void Schroeder2011::step() {
  Impl& d = *impl_;
  const double t0 = time();
  const double t1 = stepEndTime();
  const double hL = timestep();
  detail::evaluateForces(system_, d.linear, d.built, displacement_, d.internalForce, d.stiffness, stats_);
  if (!d.linear || !d.built) {
    rebuild();
    d.built = true;
  }
  Stopwatch solve;
  solve.start();
  Eigen::VectorXd boundaryImpulse = Eigen::VectorXd::Zero(system_.numDofs());
  for (int i = 0; i < partition_.numRegions(); ++i) substeps(i, t0, boundaryImpulse);
  // (S5) over the interior's free DOFs at its frame-start positions.
  Eigen::VectorXd filtered = boundaryImpulse;
  if (options_.rigidity > 0.0 && !partition_.largeDofs().empty() && boundaryImpulse.squaredNorm() > 0.0) {
    const TetMesh& mesh = *system_.mesh;
    const Eigen::VectorXd positions =
        Eigen::Map<const Eigen::VectorXd>(mesh.restPositions().data(), mesh.numDofs()) + displacement_;
    const RigidImpulseProjection projection(positions, d.lumpedMass, partition_.largeDofs());
    filtered = projection.apply(boundaryImpulse, options_.rigidity);
  }
  const Eigen::VectorXd change = d.compoundSolver->solve(coupledRightHandSide(t1, filtered));
  Eigen::VectorXd newU = displacement_, newV = velocity_;
  const std::vector<int>& free = system_.freeDofs.freeToFull();
  for (std::size_t k = 0; k < free.size(); ++k) {
    if (d.freeRegion[k] >= 0) continue;
    const int dof = free[k];
    newV[dof] = velocity_[dof] + change[static_cast<Eigen::Index>(k)];
    newU[dof] = displacement_[dof] + (hL * newV[dof]);
  }
  const std::vector<int>& fullToFree = system_.freeDofs.fullToFree();
  for (int i = 0; i < partition_.numRegions(); ++i) {
    const std::vector<int>& s = partition_.regionDofs(i);
    const double hS = d.regions[static_cast<std::size_t>(i)].smallStep;
    const Eigen::VectorXd& uS = d.lastU[static_cast<std::size_t>(i)];
    const Eigen::VectorXd& vS = d.lastV[static_cast<std::size_t>(i)];
    for (std::size_t k = 0; k < s.size(); ++k) {
      const Eigen::Index kk = static_cast<Eigen::Index>(k);
      newV[s[k]] = vS[kk] + change[fullToFree[static_cast<std::size_t>(s[k])]];
      newU[s[k]] = uS[kk] + (hS * newV[s[k]]);
    }
  }
  stats_.solveSeconds += solve.stop();
  commitStep(newU, newV);
  stats_.solvedRightHandSides = 0;
  stats_.solveFlops = 0.0;
  detail::addSolveCounts(*d.compoundSolver, stats_);
  for (const detail::FastRegion& region : d.regions) detail::addSolveCounts(*region.solver, stats_);
}

RunReport Schroeder2011::report() const {
  RunReport report;
  report.factorNonZeros = factorNonZeros();
  if (impl_->lumpedConsistentMass) {
    report.lines.emplace_back(
        "schroeder2011: the consistent mass matrix is lumped to its row sums (SKZF11's particles)");
  }
  return report;
}

long long Schroeder2011::factorNonZeros() const {
  long long total = impl_->compoundSolver->stats().factorNonZeros;
  for (const detail::FastRegion& region : impl_->regions) total += region.solver->stats().factorNonZeros;
  return total;
}

}  // namespace asyncfem
