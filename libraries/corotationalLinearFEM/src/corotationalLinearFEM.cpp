// SPDX-License-Identifier: BSD-3-Clause
#include <Eigen/Geometry>
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/corotationalLinearFEM/corotationalLinearFEM.hpp>
#include <asyncfem/corotationalLinearFEM/polarDecomposition.hpp>
#include <cmath>
#include <sstream>
#include <string>
#include <utility>

namespace asyncfem {

namespace {

using Index = std::size_t;
Index toIndex(int i) { return static_cast<Index>(i); }

/// [p]x, the matrix with [p]x q = p x q.
Eigen::Matrix3d crossMatrix(const Eigen::Vector3d& p) {
  Eigen::Matrix3d m;
  m << 0.0, -p[2], p[1], p[2], 0.0, -p[0], -p[1], p[0], 0.0;
  return m;
}

/// The element's corotated displacement v = R^T x - X (3x4, one column per vertex).
ElementPositions corotatedDisplacement(const Eigen::Matrix3d& rotation, const ElementPositions& current,
                                       const ElementPositions& rest) {
  ElementPositions v = rotation.transpose() * current;
  v -= rest;
  return v;
}

/// f_e = R K_e v (12), v = R^T x - X.
void elementForce(const ElementMatrix& stiffness, const Eigen::Matrix3d& rotation, const ElementPositions& current,
                  const ElementPositions& rest, ElementVector& out) {
  const ElementPositions v = corotatedDisplacement(rotation, current, rest);
  const ElementVector kv = stiffness * Eigen::Map<const ElementVector>(v.data());
  Eigen::Map<ElementPositions>(out.data()).noalias() = rotation * Eigen::Map<const ElementPositions>(kv.data());
}

/// R K_e R^T, block (a, b) = R K_ab R^T.
void simpleElementTangent(const ElementMatrix& stiffness, const Eigen::Matrix3d& rotation, ElementMatrix& out) {
  const Eigen::Matrix3d rotationTransposed = rotation.transpose();
  for (int b = 0; b < 4; ++b) {
    for (int a = 0; a < 4; ++a) {
      const Eigen::Matrix3d rotatedRight = stiffness.block<3, 3>(3 * a, 3 * b) * rotationTransposed;
      out.block<3, 3>(3 * a, 3 * b).noalias() = rotation * rotatedRight;
    }
  }
}

/// d f_e / d x = R (K_e R^T + (Z + K_e Y) W), symmetrised; see the class comment for Z,
/// Y and W. differentialOperator is (tr S I - S)^{-1}.
void exactElementTangent(const ElementMatrix& stiffness, const Eigen::Matrix3d& rotation,
                         const Eigen::Matrix3d& differentialOperator, const Eigen::Matrix<double, 3, 4>& gradients,
                         const ElementPositions& current, const ElementPositions& rest, ElementMatrix& out) {
  const ElementPositions corotatedPositions = rotation.transpose() * current;  // y = R^T x
  const ElementPositions v = corotatedPositions - rest;
  const ElementVector kv = stiffness * Eigen::Map<const ElementVector>(v.data());

  // Column 3a + c of W: the axial vector w of R^T dR for a unit change of coordinate c
  // of vertex a. There dF = e_c g_a^T, so R^T dF - dF^T R = r_c g_a^T - g_a r_c^T with
  // axial vector g_a x r_c.
  Eigen::Matrix<double, 3, 12> w;
  for (int a = 0; a < 4; ++a) {
    const Eigen::Vector3d g = gradients.col(a);
    for (int c = 0; c < 3; ++c) {
      const Eigen::Vector3d rowOfRotation = rotation.row(c).transpose();
      w.col((3 * a) + c).noalias() = differentialOperator * g.cross(rowOfRotation);
    }
  }
  // d(R^T x_b) from dR = R [w]x is -[w]x y_b = [y_b]x w, and dR (K v)_b = -R [(K v)_b]x w.
  Eigen::Matrix<double, 12, 3> rotationResponse = Eigen::Matrix<double, 12, 3>::Zero();
  for (int b = 0; b < 4; ++b) {
    rotationResponse.noalias() += stiffness.middleCols<3>(3 * b) * crossMatrix(corotatedPositions.col(b));
  }
  for (int b = 0; b < 4; ++b) rotationResponse.middleRows<3>(3 * b) -= crossMatrix(kv.segment<3>(3 * b));

  ElementMatrix inner;  // K R^T + (Z + K Y) W, before the final rotation
  const Eigen::Matrix3d rotationTransposed = rotation.transpose();
  for (int b = 0; b < 4; ++b) {
    for (int a = 0; a < 4; ++a) {
      inner.block<3, 3>(3 * a, 3 * b).noalias() = stiffness.block<3, 3>(3 * a, 3 * b) * rotationTransposed;
    }
  }
  inner.noalias() += rotationResponse * w;
  for (int b = 0; b < 4; ++b) {
    for (int a = 0; a < 4; ++a) {
      out.block<3, 3>(3 * a, 3 * b).noalias() = rotation * inner.block<3, 3>(3 * a, 3 * b);
    }
  }
  // The Hessian of the energy is symmetric; averaging removes the rounding asymmetry.
  for (int j = 0; j < 12; ++j) {
    for (int i = j + 1; i < 12; ++i) {
      const double average = 0.5 * (out(i, j) + out(j, i));
      out(i, j) = average;
      out(j, i) = average;
    }
  }
}

}  // namespace

CorotationalLinearFEM::CorotationalLinearFEM(const TetMesh& mesh, TangentKind tangentKind)
    : CorotationalLinearFEM(mesh, std::make_shared<const MatrixAssembler>(mesh), tangentKind) {}

CorotationalLinearFEM::CorotationalLinearFEM(const TetMesh& mesh, std::shared_ptr<const MatrixAssembler> assembler,
                                             TangentKind tangentKind)
    : assembler_(std::move(assembler)),
      tangentKind_(tangentKind),
      numDofs_(mesh.numDofs()),
      elements_(mesh.elements()) {
  if (!assembler_) throw Error("CorotationalLinearFEM: the assembler is null");
  if (assembler_->numDofs() != mesh.numDofs() || assembler_->numElements() != mesh.numElements()) {
    throw Error("CorotationalLinearFEM: the assembler was built for a mesh with " +
                std::to_string(assembler_->numDofs() / 3) + " vertices and " +
                std::to_string(assembler_->numElements()) + " elements, not " + std::to_string(mesh.numVertices()) +
                " and " + std::to_string(mesh.numElements()));
  }
  const int numElements = mesh.numElements();
  const Index count = toIndex(numElements);
  restPositions_.resize(count);
  shapeGradients_.resize(count);
  elementStiffness_.resize(count);
  rotations_.assign(count, Eigen::Matrix3d::Identity());
  elementEnergies_.assign(count, 0.0);
  std::vector<double> signedVolumes(count);
  std::vector<double> longestEdges(count);
#pragma omp parallel for schedule(static)
  for (int e = 0; e < numElements; ++e) {
    const Index i = toIndex(e);
    const ElementPositions x = mesh.elementRestPositions(e);
    restPositions_[i] = x;
    shapeGradients_[i] = shapeFunctionGradients(x, &signedVolumes[i]);
    double longestSquared = 0.0;
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) longestSquared = std::max(longestSquared, (x.col(a) - x.col(b)).squaredNorm());
    longestEdges[i] = std::sqrt(longestSquared);
    const Material& material = mesh.elementMaterial(e);
    elementStiffness_[i] = linearElementStiffness(x, material.youngsModulus, material.poissonRatio);
  }
  // Checked after the loop, in element order, so the error names the lowest element
  // whatever the thread count.
  for (int e = 0; e < numElements; ++e) {
    const Index i = toIndex(e);
    const double limit = 1e-14 * longestEdges[i] * longestEdges[i] * longestEdges[i];
    if (!(std::abs(signedVolumes[i]) > limit) || !std::isfinite(signedVolumes[i])) {
      std::ostringstream message;
      message << "CorotationalLinearFEM: element " << e << " is degenerate (signed volume " << signedVolumes[i]
              << ", longest edge " << longestEdges[i] << ")";
      throw ValidationError(message.str());
    }
  }
}

Eigen::SparseMatrix<double> CorotationalLinearFEM::createStiffnessMatrix() const { return assembler_->createMatrix(); }

void CorotationalLinearFEM::checkDisplacement(const Eigen::VectorXd& displacement, const char* caller) const {
  if (displacement.size() != numDofs_) {
    throw Error(std::string("CorotationalLinearFEM::") + caller + ": displacement has size " +
                std::to_string(displacement.size()) + ", expected " + std::to_string(numDofs_));
  }
}

ElementPositions CorotationalLinearFEM::currentPositions(int e, const Eigen::VectorXd& displacement) const {
  ElementPositions x = restPositions_[toIndex(e)];
  for (int a = 0; a < 4; ++a) x.col(a) += displacement.segment<3>(3 * static_cast<Eigen::Index>(elements_(a, e)));
  return x;
}

void CorotationalLinearFEM::updateRotations(const Eigen::VectorXd& displacement, bool needDifferentialOperator) {
  const int numElements = this->numElements();
  if (needDifferentialOperator) differentialOperators_.resize(toIndex(numElements));
#pragma omp parallel for schedule(static)
  for (int e = 0; e < numElements; ++e) {
    const Index i = toIndex(e);
    const Eigen::Matrix3d deformationGradient = currentPositions(e, displacement) * shapeGradients_[i].transpose();
    const PolarDecomposition polar = polarDecomposition(deformationGradient);
    rotations_[i] = polar.rotation;
    if (needDifferentialOperator) differentialOperators_[i] = rotationDifferentialOperator(polar);
  }
}

void CorotationalLinearFEM::assembleForces(const Eigen::VectorXd& displacement, Eigen::VectorXd& forces) const {
  forces = assembler_->assembleVector([&](int e, ElementVector& out) {
    const Index i = toIndex(e);
    elementForce(elementStiffness_[i], rotations_[i], currentPositions(e, displacement), restPositions_[i], out);
  });
}

void CorotationalLinearFEM::assembleTangent(const Eigen::VectorXd& displacement,
                                            Eigen::SparseMatrix<double>& stiffness) const {
  if (stiffness.rows() != numDofs_ || stiffness.cols() != numDofs_ || !stiffness.isCompressed() ||
      stiffness.nonZeros() != assembler_->nonZeros()) {
    stiffness = assembler_->createMatrix();
  }
  if (tangentKind_ == TangentKind::simple) {
    assembler_->assemble(
        [&](int e, ElementMatrix& out) {
          const Index i = toIndex(e);
          simpleElementTangent(elementStiffness_[i], rotations_[i], out);
        },
        stiffness);
  } else {
    assembler_->assemble(
        [&](int e, ElementMatrix& out) {
          const Index i = toIndex(e);
          exactElementTangent(elementStiffness_[i], rotations_[i], differentialOperators_[i], shapeGradients_[i],
                              currentPositions(e, displacement), restPositions_[i], out);
        },
        stiffness);
  }
}

void CorotationalLinearFEM::internalForces(const Eigen::VectorXd& displacement, Eigen::VectorXd& forces) {
  checkDisplacement(displacement, "internalForces");
  updateRotations(displacement, false);
  assembleForces(displacement, forces);
}

void CorotationalLinearFEM::tangentStiffness(const Eigen::VectorXd& displacement,
                                             Eigen::SparseMatrix<double>& stiffness) {
  checkDisplacement(displacement, "tangentStiffness");
  updateRotations(displacement, tangentKind_ == TangentKind::exact);
  assembleTangent(displacement, stiffness);
}

void CorotationalLinearFEM::forcesAndTangent(const Eigen::VectorXd& displacement, Eigen::VectorXd& forces,
                                             Eigen::SparseMatrix<double>& stiffness) {
  checkDisplacement(displacement, "forcesAndTangent");
  updateRotations(displacement, tangentKind_ == TangentKind::exact);
  assembleForces(displacement, forces);
  assembleTangent(displacement, stiffness);
}

bool CorotationalLinearFEM::elementTangent(const Eigen::VectorXd& displacement, int element,
                                           ElementMatrix& tangent) const {
  checkDisplacement(displacement, "elementTangent");
  if (element < 0 || element >= numElements()) {
    throw Error("CorotationalLinearFEM::elementTangent: element " + std::to_string(element) + " is out of range [0, " +
                std::to_string(numElements()) + ")");
  }
  const Index i = toIndex(element);
  const ElementPositions x = currentPositions(element, displacement);
  const PolarDecomposition polar = polarDecomposition(x * shapeGradients_[i].transpose());
  if (tangentKind_ == TangentKind::simple) {
    simpleElementTangent(elementStiffness_[i], polar.rotation, tangent);
  } else {
    exactElementTangent(elementStiffness_[i], polar.rotation, rotationDifferentialOperator(polar), shapeGradients_[i],
                        x, restPositions_[i], tangent);
  }
  return true;
}

double CorotationalLinearFEM::elasticEnergy(const Eigen::VectorXd& displacement) {
  checkDisplacement(displacement, "elasticEnergy");
  updateRotations(displacement, false);
  const int numElements = this->numElements();
#pragma omp parallel for schedule(static)
  for (int e = 0; e < numElements; ++e) {
    const Index i = toIndex(e);
    const ElementPositions v =
        corotatedDisplacement(rotations_[i], currentPositions(e, displacement), restPositions_[i]);
    const Eigen::Map<const ElementVector> stacked(v.data());
    elementEnergies_[i] = 0.5 * stacked.dot(elementStiffness_[i] * stacked);
  }
  // Summed serially in element order: the total does not depend on the thread count.
  double energy = 0.0;
  for (const double elementEnergy : elementEnergies_) energy += elementEnergy;
  return energy;
}

}  // namespace asyncfem
