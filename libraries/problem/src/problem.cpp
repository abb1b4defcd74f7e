// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/core/enumNames.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/forceModel/linearForceModel.hpp>
#include <asyncfem/hexElements/hexAssembly.hpp>
#include <asyncfem/hexElements/hexCorotationalForceModel.hpp>
#include <asyncfem/hexElements/hexHyperelasticForceModel.hpp>
#include <asyncfem/hyperelasticFEM/factory.hpp>
#include <asyncfem/problem/problem.hpp>
#include <asyncfem/volumetricMesh/queries.hpp>
#include <cmath>
#include <iterator>
#include <sstream>

namespace asyncfem {

Problem::Problem(std::shared_ptr<const TetMesh> mesh, std::vector<int> fixedVertices, ProblemSettings settings,
                 std::vector<VertexLoad> windows, std::shared_ptr<const PenaltyContact> contact)
    : mesh_(std::move(mesh)),
      fixedVertices_(std::move(fixedVertices)),
      settings_(std::move(settings)),
      windows_(std::move(windows)),
      contact_(std::move(contact)) {
  if (!mesh_) throw ValidationError("problem: no mesh");
  if (mesh_->isHexahedral()) requireHexahedralModel();
  if (settings_.implicitContact && contact_ && contact_->parameters().friction > 0.0) {
    std::ostringstream friction;
    friction << contact_->parameters().friction;
    throw ValidationError(
        "problem: implicit contact with friction " + friction.str() +
        ": friction is not treated implicitly (its force grows with the depth, a coupling Newton's symmetric step "
        "matrix cannot hold); set the friction to 0 or treat contact explicitly");
  }
  const int n = mesh_->numVertices();
  std::sort(fixedVertices_.begin(), fixedVertices_.end());
  fixedVertices_.erase(std::unique(fixedVertices_.begin(), fixedVertices_.end()), fixedVertices_.end());
  for (const int v : fixedVertices_) {
    if (v < 0 || v >= n) {
      throw ValidationError("problem: fixed vertex " + std::to_string(v) + " out of range [0, " + std::to_string(n) +
                            ")");
    }
  }
  if (!fixedVertices_.empty() && static_cast<int>(fixedVertices_.size()) == n) {
    throw ValidationError("problem: every vertex is fixed: nothing would move");
  }
  unusedVertices_ = asyncfem::unusedVertices(*mesh_);
  const std::vector<int> held = heldVertices();
  if (static_cast<int>(held.size()) == n && n > 0) {
    throw ValidationError("problem: every vertex is fixed or in no element: nothing would move");
  }
  for (const VertexLoad& load : windows_) {
    for (const int v : load.vertices) {
      if (v < 0 || v >= n) {
        throw ValidationError("problem: load vertex " + std::to_string(v) + " out of range [0, " + std::to_string(n) +
                              ")");
      }
    }
  }
  freeDofs_ = FreeDofs::fromFixedVertices(n, held);
}

void Problem::requireHexahedralModel() const {
  const HyperelasticOptions& options = settings_.hyperelastic;
  if (settings_.forceModel == ForceModelType::stvk && options.stvkFormulation == StVKFormulation::greenStrain &&
      (options.inversionHandlingEnabled() || options.enableCompressionResistance || options.enforceSPD)) {
    throw ValidationError(
        "problem: StVK on hexahedra in the Green-strain form (HexStvkForceModel) has no inversion threshold, "
        "compression resistance or enforceSPD: choose the principal-stretch formulation for them");
  }
}

std::vector<int> Problem::heldVertices() const {
  std::vector<int> held;
  held.reserve(fixedVertices_.size() + unusedVertices_.size());
  std::set_union(fixedVertices_.begin(), fixedVertices_.end(), unusedVertices_.begin(), unusedVertices_.end(),
                 std::back_inserter(held));
  return held;
}

const std::shared_ptr<const MatrixAssembler>& Problem::assembler() const {
  mesh_->requireTetrahedra("Problem::assembler() (the tetrahedral assembly)");
  if (!assembler_) assembler_ = std::make_shared<const MatrixAssembler>(*mesh_);
  return assembler_;
}

const Eigen::SparseMatrix<double>& Problem::massMatrix() const {
  if (!haveMass_) {
    mass_ = mesh_->isHexahedral() ? hexMassMatrix(*mesh_, settings_.mass)
                                  : asyncfem::massMatrix(*mesh_, *assembler(), settings_.mass);
    haveMass_ = true;
    ++assemblies_;
  }
  return mass_;
}

const Eigen::SparseMatrix<double>& Problem::stiffnessMatrix() const {
  if (!haveStiffness_) {
    stiffness_ = mesh_->isHexahedral() ? hexLinearStiffnessMatrix(*mesh_) : linearStiffnessMatrix(*mesh_, *assembler());
    haveStiffness_ = true;
    ++assemblies_;
  }
  return stiffness_;
}

const std::shared_ptr<const Loads>& Problem::loads() const {
  if (!loads_) {
    auto loads = std::make_shared<Loads>();
    if (!settings_.gravity.isZero(0.0)) {
      loads->addConstant(massMatrix() * settings_.gravity.replicate(mesh_->numVertices(), 1));
    }
    for (const VertexLoad& load : windows_) loads->addWindow(load);
    loads->setContact(contact_);
    loads_ = std::move(loads);
  }
  return loads_;
}

namespace {

// Names of the force models that are not a hyperelastic material; the others are
// written as their material.
constexpr EnumName<ForceModelType> kForceModelNames[] = {{ForceModelType::linear, "linear"},
                                                         {ForceModelType::corotational, "corotational"}};

// The material of a hyperelastic force model, or nullopt for the others.
std::optional<HyperelasticMaterialKind> hyperelasticMaterial(ForceModelType type) {
  switch (type) {
    case ForceModelType::stvk:
      return HyperelasticMaterialKind::stvk;
    case ForceModelType::neoHookean:
      return HyperelasticMaterialKind::neoHookean;
    case ForceModelType::mooneyRivlin:
      return HyperelasticMaterialKind::mooneyRivlin;
    default:
      return std::nullopt;
  }
}

}  // namespace

std::string toString(ForceModelType type) {
  if (const std::optional<HyperelasticMaterialKind> material = hyperelasticMaterial(type)) return toString(*material);
  return std::string(findEnumName(kForceModelNames, type).value_or("unknown"));
}

std::shared_ptr<ForceModel> Problem::makeForceModel() const {
  switch (settings_.forceModel) {
    case ForceModelType::linear:
      return std::make_shared<LinearForceModel>(stiffnessMatrix());
    case ForceModelType::corotational:
      if (mesh_->isHexahedral()) {
        return std::make_shared<HexCorotationalForceModel>(*mesh_, settings_.tangent == TangentKind::simple);
      }
      return std::make_shared<CorotationalLinearFEM>(*mesh_, assembler(), settings_.tangent);
    case ForceModelType::stvk:
    case ForceModelType::neoHookean:
    case ForceModelType::mooneyRivlin: {
      const HyperelasticMaterialKind kind = *hyperelasticMaterial(settings_.forceModel);
      if (mesh_->isHexahedral()) return makeHexHyperelasticForceModel(*mesh_, kind, settings_.hyperelastic);
      return makeHyperelasticForceModel(*mesh_, kind, settings_.hyperelastic, assembler());
    }
  }
  throw ValidationError("problem: unknown force model type");
}

DynamicSystem Problem::dynamicSystem() const {
  DynamicSystem system;
  system.forceModel = makeForceModel();
  system.mass = massMatrix();
  system.freeDofs = freeDofs_;
  system.rayleighMass = settings_.rayleighAlpha;
  system.rayleighStiffness = settings_.rayleighBeta;
  system.mesh = mesh_;
  std::shared_ptr<const Loads> external = loads();
  if (!external->empty()) {
    system.externalForce = [external](double time, const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity,
                                      Eigen::VectorXd& forces) {
      external->addTo(time, displacement, velocity, forces);
    };
    system.externalForceAt = [external](double time, const Eigen::VectorXd& displacement,
                                        const Eigen::VectorXd& velocity, const std::vector<int>& vertices,
                                        Eigen::VectorXd& forces) {
      external->addTo(time, displacement, velocity, vertices, forces);
    };
    if (contact_ && contact_->surfaces()) {
      system.externalForceOfRank = [external, implicit = settings_.implicitContact](
                                       double time, const Eigen::VectorXd& displacement,
                                       const Eigen::VectorXd& velocity, const std::vector<int>& vertices,
                                       const std::vector<int>& rank, int owner, Eigen::VectorXd& forces,
                                       VertexJacobian* jacobian) {
        if (jacobian != nullptr && !implicit) jacobian->clear();  // explicit contact: no derivatives
        external->addTo(time, displacement, velocity, vertices, rank, owner, forces, implicit ? jacobian : nullptr);
      };
    }
    // Gravity is constant and contact depends on the state only; the windows open and
    // close at their bounds. A bound within a millionth of the interval of it counts as
    // inside, so that the snapping of bounds to step times never makes the answer wrong.
    // A moving obstacle changes the force at any time.
    const bool moving = contact_ && contact_->timeDependent();
    system.externalForceChanges = [breakpoints = external->breakpoints(), moving](double from, double to) {
      if (moving) return true;
      const double slack = 1e-6 * std::abs(to - from);
      const auto first = std::lower_bound(breakpoints.begin(), breakpoints.end(), from - slack);
      return first != breakpoints.end() && *first <= to + slack;
    };
  }
  if (contact_) {
    system.obstacleProximity = [contact = contact_](const Eigen::VectorXd& displacement, double margin,
                                                    std::vector<int>& vertices) {
      vertices = contact->verticesWithin(displacement, margin);
    };
    // The loads' only state-dependent part is the penalty force, zero out of contact.
    system.stateDependentOnlyInContact = !contact_->timeDependent();
    if (settings_.implicitContact) {
      system.externalForceJacobian = [contact = contact_](double time, const Eigen::VectorXd& displacement,
                                                          const Eigen::VectorXd& velocity, VertexJacobian& jacobian) {
        jacobian = contact->jacobian(time, displacement, velocity);
      };
      system.externalForceJacobianAt =
          [contact = contact_](double time, const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity,
                               const std::vector<int>& vertices, VertexJacobian& jacobian) {
            jacobian = contact->jacobian(time, displacement, velocity, &vertices);
          };
      if (contact_->surfaces()) {
        system.externalForceCoupledJacobian = [contact = contact_](double time, const Eigen::VectorXd& displacement,
                                                                   const Eigen::VectorXd& velocity,
                                                                   VertexJacobian& jacobian) {
          jacobian = contact->coupledJacobian(time, displacement, velocity);
        };
      }
    }
  }
  return system;
}

std::vector<std::string> Problem::skipped() const {
  std::vector<std::string> skipped;
  if (settings_.forceModel == ForceModelType::linear) {
    skipped.emplace_back("corotational rotations and per-step tangent (linear force model)");
  }
  if (settings_.gravity.isZero(0.0)) skipped.emplace_back("gravity load (gravity is zero)");
  if (!contact_) skipped.emplace_back("contact (no obstacles)");
  if (!unusedVertices_.empty()) {
    skipped.push_back("free DOFs of " + std::to_string(unusedVertices_.size()) +
                      " vertex(es) that no element uses (held at rest)");
  }
  if (settings_.gravity.isZero(0.0) && windows_.empty() && !contact_) {
    skipped.emplace_back("external force evaluation (no gravity, no loads)");
  }
  return skipped;
}

}  // namespace asyncfem
