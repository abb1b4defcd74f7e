// SPDX-License-Identifier: BSD-3-Clause
// Deformations, evaluations and finite differences shared by the force-model tests
// (corotationalLinearFEM, hyperelasticFEM): anything that is a ForceModel.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/SparseCore>
#include <asyncfem/forceModel/forceModel.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <random>

namespace asyncfem::test {

/// A uniformly distributed rotation (normalised Gaussian quaternion), reproducible.
inline Eigen::Matrix3d randomRotation(std::mt19937& random) {
  std::normal_distribution<double> normal;
  Eigen::Quaterniond q(normal(random), normal(random), normal(random), normal(random));
  q.normalize();
  return q.toRotationMatrix();
}

/// Displacement (3n) of x = Q (X + d) + t with d uniform in [-amplitude, amplitude]^3 per
/// vertex: a random deformation (strain about amplitude / cell size) followed by a rigid
/// motion.
inline Eigen::VectorXd deformedDisplacement(const TetMesh& mesh, const Eigen::Matrix3d& rotation,
                                            const Eigen::Vector3d& translation, double amplitude,
                                            std::mt19937& random) {
  std::uniform_real_distribution<double> offset(-amplitude, amplitude);
  Eigen::VectorXd u(mesh.numDofs());
  for (int v = 0; v < mesh.numVertices(); ++v) {
    const Eigen::Vector3d x = mesh.restPosition(v);
    const Eigen::Vector3d d(offset(random), offset(random), offset(random));
    u.segment<3>(3 * v) = rotation * (x + d) + translation - x;
  }
  return u;
}

inline Eigen::VectorXd forces(ForceModel& model, const Eigen::VectorXd& u) {
  Eigen::VectorXd f;
  model.internalForces(u, f);
  return f;
}

inline Eigen::MatrixXd tangent(ForceModel& model, const Eigen::VectorXd& u) {
  Eigen::SparseMatrix<double> k = model.createStiffnessMatrix();
  model.tangentStiffness(u, k);
  return Eigen::MatrixXd(k);
}

/// Central differences of the forces, column j = (f(u + t e_j) - f(u - t e_j)) / 2t.
inline Eigen::MatrixXd finiteDifferenceTangent(ForceModel& model, const Eigen::VectorXd& u, double step) {
  Eigen::MatrixXd result(u.size(), u.size());
  for (Eigen::Index j = 0; j < u.size(); ++j) {
    Eigen::VectorXd plus = u;
    Eigen::VectorXd minus = u;
    plus[j] += step;
    minus[j] -= step;
    result.col(j) = (forces(model, plus) - forces(model, minus)) / (2.0 * step);
  }
  return result;
}

/// max |a - b| / max |b| over the entries (two evaluations of the same quantity).
inline double relativeEntryDifference(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return (a - b).cwiseAbs().maxCoeff() / b.cwiseAbs().maxCoeff();
}

/// The same over the stored values of two matrices of one pattern.
inline double relativeEntryDifference(const Eigen::SparseMatrix<double>& a, const Eigen::SparseMatrix<double>& b) {
  const Eigen::Map<const Eigen::VectorXd> va(a.valuePtr(), a.nonZeros());
  const Eigen::Map<const Eigen::VectorXd> vb(b.valuePtr(), b.nonZeros());
  return relativeEntryDifference(va, vb);
}

}  // namespace asyncfem::test
