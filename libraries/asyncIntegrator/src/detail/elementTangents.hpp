// SPDX-License-Identifier: BSD-3-Clause
// Where an element's tangent comes from, for the couplings that need one per element (the
// stable coupling's interface elements, the hierarchy solve, Schroeder et al. 2011's
// interface). Private to the library.
#pragma once

#include <Eigen/Core>
#include <asyncfem/forceModel/forceModel.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <string>

namespace asyncfem::detail {

/// The tangent K_e (N/m; 12 x 12 on tetrahedra, 24 x 24 on hexahedra) of element e: the
/// force model's elementTangentOfAnyKind() where it gives one, otherwise (a linear model
/// built from a matrix) the mesh's linear FEM element stiffness (meshElements.hpp), constant. Whoever uses the fallback
/// must check that the model's K is that stiffness (the callers do, on the columns they need).
class ElementTangents {
 public:
  /// Probes model on element 0 at rest. Throws asyncfem::ValidationError "<who>: ..." for a
  /// nonlinear model that gives no element tangent (hint: what the caller suggests instead,
  /// appended to the message; may be empty).
  ElementTangents(const TetMesh& mesh, const ForceModel& model, const std::string& who, const std::string& hint = "");

  /// Whether the force model gives per-element tangents (else the linear fallback).
  bool perElement() const { return perElement_; }
  /// K_e at displacement u (3n).
  void tangent(const Eigen::VectorXd& u, int e, Eigen::MatrixXd& out) const;
  /// The mesh's linear FEM stiffness of element e.
  Eigen::MatrixXd linear(int e) const;

 private:
  const TetMesh& mesh_;
  const ForceModel& model_;
  bool perElement_ = false;
};

}  // namespace asyncfem::detail
