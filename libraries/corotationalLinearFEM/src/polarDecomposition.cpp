// SPDX-License-Identifier: BSD-3-Clause
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <asyncfem/corotationalLinearFEM/polarDecomposition.hpp>
#include <cmath>
#include <limits>

namespace asyncfem {

PolarDecomposition polarDecomposition(const Eigen::Matrix3d& deformationGradient) {
  // F is square, so the QR preconditioning step of JacobiSVD (meant for rectangular
  // matrices) only costs time: without it the decomposition is about twice as fast.
  const Eigen::JacobiSVD<Eigen::Matrix3d, Eigen::NoQRPreconditioner> svd(deformationGradient,
                                                                         Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d u = svd.matrixU();
  Eigen::Matrix3d v = svd.matrixV();
  Eigen::Vector3d sigma = svd.singularValues();
  // Flipping a column of U (or V) together with the sign of the matching singular value
  // leaves U diag(sigma) V^T unchanged; the smallest one is flipped so that an inverted
  // element is treated as compressed through its thinnest direction.
  if (u.determinant() < 0.0) {
    u.col(2) = -u.col(2);
    sigma[2] = -sigma[2];
  }
  if (v.determinant() < 0.0) {
    v.col(2) = -v.col(2);
    sigma[2] = -sigma[2];
  }
  PolarDecomposition polar;
  polar.rotation.noalias() = u * v.transpose();
  polar.stretch.noalias() = v * sigma.asDiagonal() * v.transpose();
  // S is symmetric in exact arithmetic; copying one triangle makes it so in floating
  // point too, which the torque-free forces rely on.
  polar.stretch(1, 0) = polar.stretch(0, 1);
  polar.stretch(2, 0) = polar.stretch(0, 2);
  polar.stretch(2, 1) = polar.stretch(1, 2);
  polar.rightSingularVectors = v;
  polar.singularValues = sigma;
  return polar;
}

Eigen::Matrix3d rotationDifferentialOperator(const PolarDecomposition& polar) {
  const Eigen::Vector3d& sigma = polar.singularValues;
  // Eigenvalues of tr(S) I - S: for eigenvector i the sum of the other two values.
  const Eigen::Vector3d pairSums(sigma[1] + sigma[2], sigma[0] + sigma[2], sigma[0] + sigma[1]);
  Eigen::Vector3d inverse;
  for (int i = 0; i < 3; ++i) inverse[i] = 1.0 / std::max(pairSums[i], kMinimumSingularValuePairSum);
  const Eigen::Matrix3d& v = polar.rightSingularVectors;
  Eigen::Matrix3d result = v * inverse.asDiagonal() * v.transpose();
  result(1, 0) = result(0, 1);
  result(2, 0) = result(0, 2);
  result(2, 1) = result(1, 2);
  return result;
}

Eigen::Matrix3d rotationDifferential(const PolarDecomposition& polar,
                                     const Eigen::Matrix3d& deformationGradientDifferential) {
  const Eigen::Matrix3d a = polar.rotation.transpose() * deformationGradientDifferential;
  const Eigen::Matrix3d skewPart = a - a.transpose();
  const Eigen::Vector3d axial(skewPart(2, 1), skewPart(0, 2), skewPart(1, 0));
  const Eigen::Vector3d w = rotationDifferentialOperator(polar) * axial;
  Eigen::Matrix3d cross;
  cross << 0.0, -w[2], w[1], w[2], 0.0, -w[0], -w[1], w[0], 0.0;
  return polar.rotation * cross;
}

}  // namespace asyncfem

namespace asyncfem {

namespace {

// Newton steps before giving up on an element and taking the SVD.
constexpr int kMaxNewtonSteps = 12;
// Below this step (radians) the next step would be O(step^2), under rounding.
constexpr double kConvergedStep = 1e-9;
// Newton is used while the smallest eigenvalue of tr(S) I - S (the smallest pair sum of
// singular values) is at least this fraction of its trace, and above the clamp of the
// exact tangent; closer to a point where R is not differentiable the SVD is more robust.
constexpr double kRelativePairSumMargin = 1e-3;

// A starting rotation computed from F only: the identity when F is within about 0.3
// degrees of symmetric (|axial(F - F^T)| <= tr(F) / 100), else the rotation whose first
// two columns are those of F (or of one Newton-Schulz step from F) orthonormalised.
Eigen::Matrix3d deterministicStart(const Eigen::Matrix3d& f) {
  const Eigen::Vector3d skew(f(2, 1) - f(1, 2), f(0, 2) - f(2, 0), f(1, 0) - f(0, 1));
  const double trace = f.trace();
  if (trace > 0.0 && skew.norm() <= 0.01 * trace) return Eigen::Matrix3d::Identity();
  // Near a rotation (|F^T F - I| < 1/2, strains below ~20%) one Newton-Schulz step
  // X = F (3 I - F^T F) / 2 removes the stretch to second order before the columns are
  // orthonormalised, so the Newton iteration starts a step closer.
  const Eigen::Matrix3d gram = f.transpose() * f;
  Eigen::Matrix3d x = f;
  if ((gram - Eigen::Matrix3d::Identity()).squaredNorm() < 0.25) {
    Eigen::Matrix3d factor = -0.5 * gram;
    factor.diagonal().array() += 1.5;
    x = f * factor;
  }
  const double norm0 = x.col(0).norm();
  if (!(norm0 > 0.0)) return Eigen::Matrix3d::Identity();
  const Eigen::Vector3d r0 = x.col(0) / norm0;
  Eigen::Vector3d r1 = x.col(1) - (r0.dot(x.col(1)) * r0);
  const double norm1 = r1.norm();
  if (!(norm1 > 1e-8 * norm0)) return Eigen::Matrix3d::Identity();
  r1 /= norm1;
  Eigen::Matrix3d start;
  start.col(0) = r0;
  start.col(1) = r1;
  start.col(2) = r0.cross(r1);
  return start;
}

// exp([w]x) by Rodrigues' formula.
Eigen::Matrix3d rotationExponential(const Eigen::Vector3d& w) {
  const double angleSquared = w.squaredNorm();
  double sinc = 0.0;
  double cosc = 0.0;  // (1 - cos t) / t^2
  if (angleSquared < 1e-8) {
    sinc = 1.0 - (angleSquared / 6.0);
    cosc = 0.5 - (angleSquared / 24.0);
  } else {
    const double angle = std::sqrt(angleSquared);
    sinc = std::sin(angle) / angle;
    cosc = (1.0 - std::cos(angle)) / angleSquared;
  }
  Eigen::Matrix3d cross;
  cross << 0.0, -w[2], w[1], w[2], 0.0, -w[0], -w[1], w[0], 0.0;
  Eigen::Matrix3d result = Eigen::Matrix3d::Identity() + (sinc * cross);
  result.noalias() += cosc * (cross * cross);
  return result;
}

// tr(S) I - S for S = sym(R^T F), its adjugate and determinant; false unless it is
// safely positive definite (see kRelativePairSumMargin).
struct NewtonSystem {
  Eigen::Vector3d gradient;  // axial(B - B^T), B = R^T F
  Eigen::Matrix3d adjugate;
  double determinant = 0.0;
  bool positiveDefinite = false;
};

NewtonSystem newtonSystem(const Eigen::Matrix3d& rotation, const Eigen::Matrix3d& f) {
  const Eigen::Matrix3d b = rotation.transpose() * f;
  NewtonSystem system;
  system.gradient = Eigen::Vector3d(b(2, 1) - b(1, 2), b(0, 2) - b(2, 0), b(1, 0) - b(0, 1));
  const double m00 = b(1, 1) + b(2, 2);
  const double m11 = b(0, 0) + b(2, 2);
  const double m22 = b(0, 0) + b(1, 1);
  const double m01 = -0.5 * (b(0, 1) + b(1, 0));
  const double m02 = -0.5 * (b(0, 2) + b(2, 0));
  const double m12 = -0.5 * (b(1, 2) + b(2, 1));
  Eigen::Matrix3d& adj = system.adjugate;
  adj(0, 0) = (m11 * m22) - (m12 * m12);
  adj(0, 1) = (m02 * m12) - (m01 * m22);
  adj(0, 2) = (m01 * m12) - (m02 * m11);
  adj(1, 1) = (m00 * m22) - (m02 * m02);
  adj(1, 2) = (m01 * m02) - (m00 * m12);
  adj(2, 2) = (m00 * m11) - (m01 * m01);
  adj(1, 0) = adj(0, 1);
  adj(2, 0) = adj(0, 2);
  adj(2, 1) = adj(1, 2);
  system.determinant = (m00 * adj(0, 0)) + (m01 * adj(0, 1)) + (m02 * adj(0, 2));
  // Sylvester's criterion, then a lower bound of the smallest eigenvalue: lambda_min >=
  // det / (lambda_mid lambda_max) >= 4 det / tr^2.
  const double trace = m00 + m11 + m22;
  const double smallestBound = 4.0 * system.determinant / (trace * trace);
  system.positiveDefinite = m00 > 0.0 && adj(2, 2) > 0.0 && system.determinant > 0.0 &&
                            smallestBound > std::max(kRelativePairSumMargin * trace, kMinimumSingularValuePairSum);
  return system;
}

PolarRotation fromDecomposition(const Eigen::Matrix3d& f, bool withDifferentialOperator, int steps) {
  const PolarDecomposition polar = polarDecomposition(f);
  PolarRotation result;
  result.rotation = polar.rotation;
  if (withDifferentialOperator) result.differentialOperator = rotationDifferentialOperator(polar);
  result.newtonSteps = steps;
  result.usedDecomposition = true;
  return result;
}

// The result for a non-finite F: NaN rotation and operator. The SVD of a non-finite
// matrix may come out finite; callers detect blow-ups by non-finite results, so make that
// explicit.
PolarRotation nonFiniteRotation() {
  PolarRotation result;
  result.rotation.setConstant(std::numeric_limits<double>::quiet_NaN());
  result.differentialOperator.setConstant(std::numeric_limits<double>::quiet_NaN());
  result.usedDecomposition = false;
  return result;
}

}  // namespace

PolarRotation polarRotation(const Eigen::Matrix3d& deformationGradient, const Eigen::Matrix3d* warmStart,
                            bool withDifferentialOperator) {
  const Eigen::Matrix3d& f = deformationGradient;
  // Rounding of B = R^T F is a few ulps of |F|: a gradient below this is noise.
  const double gradientFloor = 8.0 * std::numeric_limits<double>::epsilon() * f.norm();
  if (!f.allFinite()) return nonFiniteRotation();
  PolarRotation result;
  result.rotation = warmStart != nullptr ? *warmStart : deterministicStart(f);
  NewtonSystem system = newtonSystem(result.rotation, f);
  if (warmStart != nullptr && !system.positiveDefinite) {
    // The element turned too far since its last rotation (or inverted): start afresh.
    result.rotation = deterministicStart(f);
    system = newtonSystem(result.rotation, f);
  }
  for (int step = 0;; ++step) {
    if (!system.positiveDefinite) return fromDecomposition(f, withDifferentialOperator, step);
    if (system.gradient.norm() <= gradientFloor) break;
    if (step == kMaxNewtonSteps) return fromDecomposition(f, withDifferentialOperator, step);
    Eigen::Vector3d w = (system.adjugate * system.gradient) / system.determinant;
    const double angle = w.norm();
    // A long step means a start far from R, where the quadratic model is poor: limit it
    // to 1 rad (still an ascent direction of tr(R^T F)).
    if (angle > 1.0) w /= angle;
    result.rotation = result.rotation * rotationExponential(w);
    result.newtonSteps = step + 1;
    if (angle < kConvergedStep) {
      if (withDifferentialOperator) system = newtonSystem(result.rotation, f);
      break;
    }
    system = newtonSystem(result.rotation, f);
  }
  if (withDifferentialOperator) result.differentialOperator = system.adjugate / system.determinant;
  return result;
}

}  // namespace asyncfem
