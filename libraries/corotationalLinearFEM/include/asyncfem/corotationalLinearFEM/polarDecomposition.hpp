// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>

namespace asyncfem {

/// Rotation-variant polar decomposition F = R S of a 3x3 deformation gradient
/// (dimensionless), computed through the SVD F = U diag(sigma) V^T.
///
/// Sign fix (Irving, Teran & Fedkiw 2004): the SVD is taken with sigma >= 0 sorted
/// descending; if det U < 0 the last column of U and sigma_2 change sign, and the same
/// for V. Then det U = det V = +1, so R = U V^T is a proper rotation (det R = +1) for
/// every F, including flat (det F = 0) and inverted (det F < 0) ones, and
/// S = V diag(sigma) V^T is symmetric; for det F < 0 its smallest eigenvalue is
/// negative, i.e. the element is un-inverted along its thinnest direction.
///
/// Why the SVD and not an iterative polar decomposition: the iterations (Newton or
/// Higham's scaled variant) converge to the orthogonal factor with det = sign(det F),
/// i.e. to a reflection for an inverted element, and slow down as det F -> 0. The
/// closed-form tangent also needs the singular values (see rotationDifferential()).
/// A 3x3 Jacobi SVD costs about as much as a few polar iterations and is accurate to
/// rounding, which the momentum-conservation identities of the corotational forces rely
/// on (S must be symmetric).
struct PolarDecomposition {
  Eigen::Matrix3d rotation;              ///< R = U V^T, det R = +1
  Eigen::Matrix3d stretch;               ///< S = R^T F = V diag(sigma) V^T, symmetric
  Eigen::Matrix3d rightSingularVectors;  ///< V, det V = +1
  Eigen::Vector3d singularValues;        ///< sigma, |sigma| descending; sigma_2 < 0 iff det F < 0
};

/// Polar decomposition of deformationGradient (3x3) as documented on PolarDecomposition.
/// Deterministic (the result depends only on the input). Throws nothing; a non-finite
/// input gives a non-finite result.
PolarDecomposition polarDecomposition(const Eigen::Matrix3d& deformationGradient);

/// Smallest value of sigma_i + sigma_j (i != j) used by rotationDifferential(). The
/// pair sums are >= 0 after the sign fix and vanish only where R is not differentiable
/// (two singular values zero, or an inversion with sigma_1 = -sigma_2); clamping them
/// here keeps the exact tangent finite there. Dimensionless, like sigma.
inline constexpr double kMinimumSingularValuePairSum = 1e-6;

/// Differential dR of the polar rotation for a change dF of the deformation gradient.
///
/// From F = R S: R^T dF = W S + dS with W = R^T dR skew and dS symmetric; the skew part
/// gives W S + S W = R^T dF - dF^T R. Writing W = [w]x (W y = w x y), the identity
/// [w]x S + S [w]x = [(tr(S) I - S) w]x for symmetric S yields
///     (tr(S) I - S) w = axial(R^T dF - dF^T R),   dR = R [w]x,
/// where axial(A) = (A_21, A_02, A_10). In the SVD basis tr(S) I - S =
/// V diag(sigma_1 + sigma_2, sigma_0 + sigma_2, sigma_0 + sigma_1) V^T, so the solve is
/// a diagonal scaling; each pair sum is clamped below by kMinimumSingularValuePairSum.
Eigen::Matrix3d rotationDifferential(const PolarDecomposition& polar,
                                     const Eigen::Matrix3d& deformationGradientDifferential);

/// (tr(S) I - S)^{-1} = V diag(1 / max(sigma_j + sigma_k, kMinimumSingularValuePairSum)) V^T
/// (3x3, symmetric): the linear map from axial(R^T dF - dF^T R) to the axial vector w of
/// R^T dR used by rotationDifferential() and the exact corotational tangent.
Eigen::Matrix3d rotationDifferentialOperator(const PolarDecomposition& polar);

/// Result of polarRotation().
struct PolarRotation {
  Eigen::Matrix3d rotation;  ///< R, det R = +1: the rotation of polarDecomposition() to rounding
  /// (tr(S) I - S)^{-1} at R (see rotationDifferentialOperator()); filled only when asked for.
  Eigen::Matrix3d differentialOperator;
  int newtonSteps = 0;             ///< Newton steps taken (0: the start was already the answer)
  bool usedDecomposition = false;  ///< fell back to polarDecomposition() (SVD)
};

/// The rotation R of the polar decomposition F = R S (the same R as polarDecomposition(),
/// including the sign fix for flat and inverted elements), by Newton's method on SO(3).
///
/// R maximises tr(R^T F) over rotations (the orthogonal Procrustes problem); its only
/// local maximum is the SVD answer U diag(1, 1, det(U V^T)) V^T. Writing R' = R exp([w]x)
/// and B = R^T F, tr(R'^T F) = tr(B) + w . a - 1/2 w^T (tr(S) I - S) w + O(|w|^3) with
/// a = axial(B - B^T) and S = sym(B), so a Newton step is
///     (tr(S) I - S) w = a,   R <- R exp([w]x)   (Rodrigues' formula),
/// the update used by the rotation extraction of Mueller, Bender, Chentanez & Macklin
/// 2016 with their 1 / tr(S) scaling replaced by the full 3x3 solve, so that convergence
/// is quadratic. It stops when the step is below 1e-9 rad (the next one would be under
/// rounding) or a is at rounding level, and falls back to polarDecomposition() when
/// tr(S) I - S is not safely positive definite at an iterate (near-degenerate inverted
/// elements, where R is ill-conditioned, or a start far from R) or after 12 steps, so the
/// result is always a proper rotation (finite F) and never a reflection.
///
/// Start: warmStart when given (e.g. the element's rotation at its previous evaluation;
/// 1-3 steps for smooth motion) unless tr(S) I - S is not positive definite there;
/// otherwise a deterministic guess from F alone (the
/// identity for F within about 0.3 degrees of symmetric, else the Gram-Schmidt rotation
/// of the columns of F, or of one Newton-Schulz step X = F (3 I - F^T F) / 2 when F is
/// near a rotation), so the result depends only on F. F = I (to rounding) gives exactly
/// the identity. Costs about 0.1 us per Newton step against about 1 us for the SVD.
/// When withDifferentialOperator is set, (tr(S) I - S)^{-1} is returned at the final R;
/// it equals rotationDifferentialOperator(polarDecomposition(F)) to rounding (the
/// fallback path computes exactly that). A non-finite F gives a NaN rotation and operator.
PolarRotation polarRotation(const Eigen::Matrix3d& deformationGradient, const Eigen::Matrix3d* warmStart = nullptr,
                            bool withDifferentialOperator = false);

}  // namespace asyncfem
