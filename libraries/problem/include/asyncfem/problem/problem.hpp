// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <asyncfem/corotationalLinearFEM/corotationalLinearFEM.hpp>
#include <asyncfem/dynamics/dynamicSystem.hpp>
#include <asyncfem/forceModel/forceModel.hpp>
#include <asyncfem/hyperelasticFEM/hyperelasticOptions.hpp>
#include <asyncfem/problem/loads.hpp>
#include <asyncfem/stiffnessMatrix/assembler.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <memory>
#include <string>
#include <vector>

namespace asyncfem {

/// The elastic force model of a problem: linear and corotational FEM, and the
/// hyperelastic materials of library hyperelasticFEM.
enum class ForceModelType { linear, corotational, stvk, neoHookean, mooneyRivlin };

/// "linear", "corotational", "stvk", "neo-hookean", "mooney-rivlin".
std::string toString(ForceModelType type);

/// The physics of a problem beyond its mesh, boundary and loads.
struct ProblemSettings {
  MassType mass = MassType::consistent;
  ForceModelType forceModel = ForceModelType::linear;
  TangentKind tangent = TangentKind::simple;  ///< corotational only
  HyperelasticOptions hyperelastic;           ///< stvk, neo-hookean, mooney-rivlin only
  double rayleighAlpha = 0.0;                 ///< D = alpha M + beta K
  double rayleighBeta = 0.0;
  Eigen::Vector3d gravity = Eigen::Vector3d::Zero();  ///< acceleration (length / time^2)
  /// Penalty contact treated implicitly: dynamicSystem() then carries the contact's
  /// derivatives (DynamicSystem::externalForceJacobian). No effect without contact;
  /// frictionless contact only (the constructor refuses friction > 0).
  bool implicitContact = false;
};

/// A problem to integrate in time, independent of any integrator: the resolved mesh
/// (materials applied), the fixed vertices and free DOFs, the physics settings and the
/// loads. Matrices and force models are built only when asked for, once, so tools that
/// need the mesh and the boundary (renderers, region proposals) pay for nothing else;
/// assemblies() counts what was built.
///
/// The time-dependent operator of M a + D v + f_int(u) = f_ext(t, u, v): integrators get
/// it as a DynamicSystem (dynamicSystem()), whose external force evaluates loads().
///
/// Hexahedral meshes (Vega's CUBIC .veg, Gmsh hexahedra) run every force model with K and M
/// of library hexElements (trilinear elements, 2 x 2 x 2 Gauss points): linear FEM,
/// corotational FEM (HexCorotationalForceModel; settings.tangent picks its tangent), StVK in
/// its Green-strain form (HexStvkForceModel) and the hyperelastic materials through
/// principal stretches with settings.hyperelastic (HexHyperelasticForceModel:
/// makeHexHyperelasticForceModel); assembler() refuses them with a ValidationError naming
/// the conversion.
///
/// Vertices that no element uses (a stray surface in a Gmsh or TetGen file) carry no
/// mass and no stiffness, so as free DOFs they would make every system matrix singular:
/// they are left out of the free DOFs and stay at their rest positions, without being
/// counted among the fixed vertices (unusedVertices()).
class Problem {
 public:
  /// Throws asyncfem::ValidationError for a fixed vertex out of range or when every
  /// vertex is fixed or unused, and for load vertices out of range.
  Problem(std::shared_ptr<const TetMesh> mesh, std::vector<int> fixedVertices, ProblemSettings settings,
          std::vector<VertexLoad> windows = {}, std::shared_ptr<const PenaltyContact> contact = nullptr);

  const TetMesh& mesh() const { return *mesh_; }
  const std::shared_ptr<const TetMesh>& sharedMesh() const { return mesh_; }
  const std::vector<int>& fixedVertices() const { return fixedVertices_; }  ///< sorted, unique
  /// The vertices no element uses, sorted: not free DOFs, held at rest like fixed ones.
  const std::vector<int>& unusedVertices() const { return unusedVertices_; }
  /// fixedVertices() and unusedVertices() together, sorted: every vertex without free DOFs.
  std::vector<int> heldVertices() const;
  const FreeDofs& freeDofs() const { return freeDofs_; }
  const ProblemSettings& settings() const { return settings_; }
  int numDofs() const { return 3 * mesh_->numVertices(); }
  bool hasContact() const { return contact_ != nullptr; }
  const std::shared_ptr<const PenaltyContact>& contact() const { return contact_; }
  /// The windowed loads as given (without gravity, which needs the mass matrix).
  const std::vector<VertexLoad>& windows() const { return windows_; }

  // Built on request, then kept.
  const std::shared_ptr<const MatrixAssembler>& assembler() const;
  const Eigen::SparseMatrix<double>& massMatrix() const;
  /// The linear (rest) stiffness K.
  const Eigen::SparseMatrix<double>& stiffnessMatrix() const;
  /// All external forces, gravity M g included (assembles M when gravity is not zero).
  const std::shared_ptr<const Loads>& loads() const;
  /// A new force model of the settings' type (shares the assembler and, for the linear
  /// model, the stiffness matrix).
  std::shared_ptr<ForceModel> makeForceModel() const;
  /// The DynamicSystem integrators take: a new force model, M, the free DOFs, Rayleigh
  /// coefficients and, when there is any load, an external force evaluating loads().
  DynamicSystem dynamicSystem() const;

  /// Matrices assembled so far (mass, linear stiffness), for tools that promise to build none.
  int assemblies() const { return assemblies_; }
  /// Work the problem made unnecessary, for run summaries ("gravity load (gravity is zero)", ...).
  std::vector<std::string> skipped() const;

 private:
  /// Refuses, on a hexahedral mesh, the Green-strain StVK with an inversion option it would
  /// not read (ValidationError), before any model is built.
  void requireHexahedralModel() const;

  std::shared_ptr<const TetMesh> mesh_;
  std::vector<int> fixedVertices_;
  std::vector<int> unusedVertices_;
  FreeDofs freeDofs_;
  ProblemSettings settings_;
  std::vector<VertexLoad> windows_;
  std::shared_ptr<const PenaltyContact> contact_;

  mutable std::shared_ptr<const MatrixAssembler> assembler_;
  mutable Eigen::SparseMatrix<double> mass_;
  mutable Eigen::SparseMatrix<double> stiffness_;
  mutable bool haveMass_ = false;
  mutable bool haveStiffness_ = false;
  mutable std::shared_ptr<const Loads> loads_;
  mutable int assemblies_ = 0;
};

}  // namespace asyncfem
