// SPDX-License-Identifier: BSD-3-Clause
#include "elementBatches.hpp"

#include <asyncfem/corotationalLinearFEM/polarDecomposition.hpp>
#include <cstddef>
#include <limits>

namespace asyncfem::detail {

namespace {

using Mask = Eigen::Array<bool, kElementLanes, 1>;
/// A 3x3 matrix per lane, row-major: entry (i, j) at 3 i + j.
using LaneMatrix = std::array<Lanes, 9>;
using LaneVector = std::array<Lanes, 3>;

// The constants of polarRotation() (polarDecomposition.cpp), which the lanes must follow.
constexpr int kMaxNewtonSteps = 12;
constexpr double kConvergedStep = 1e-9;
constexpr double kRelativePairSumMargin = 1e-3;

std::size_t toIndex(int i) { return static_cast<std::size_t>(i); }

LaneMatrix identity() {
  LaneMatrix m;
  for (int k = 0; k < 9; ++k) m[toIndex(k)] = Lanes::Constant((k % 4 == 0) ? 1.0 : 0.0);
  return m;
}

/// A B.
LaneMatrix multiply(const LaneMatrix& a, const LaneMatrix& b) {
  LaneMatrix c;
  for (std::size_t i = 0; i < 3; ++i)
    for (std::size_t j = 0; j < 3; ++j)
      c[(3 * i) + j] = (a[3 * i] * b[j]) + (a[(3 * i) + 1] * b[3 + j]) + (a[(3 * i) + 2] * b[6 + j]);
  return c;
}

/// A^T B.
LaneMatrix multiplyTransposed(const LaneMatrix& a, const LaneMatrix& b) {
  LaneMatrix c;
  for (std::size_t i = 0; i < 3; ++i)
    for (std::size_t j = 0; j < 3; ++j) c[(3 * i) + j] = (a[i] * b[j]) + (a[3 + i] * b[3 + j]) + (a[6 + i] * b[6 + j]);
  return c;
}

Lanes dot(const LaneVector& a, const LaneVector& b) { return (a[0] * b[0]) + (a[1] * b[1]) + (a[2] * b[2]); }

LaneMatrix select(const Mask& mask, const LaneMatrix& then, const LaneMatrix& otherwise) {
  LaneMatrix m;
  for (std::size_t k = 0; k < 9; ++k) m[k] = mask.select(then[k], otherwise[k]);
  return m;
}

/// Column j of m.
LaneVector column(const LaneMatrix& m, std::size_t j) { return {m[j], m[3 + j], m[6 + j]}; }

/// polarRotation()'s deterministic start, lane by lane: the identity for F within about
/// 0.3 degrees of symmetric, else the Gram-Schmidt rotation of the columns of F (or of
/// one Newton-Schulz step from F when F is near a rotation).
LaneMatrix deterministicStart(const LaneMatrix& f) {
  const LaneVector skew{f[7] - f[5], f[2] - f[6], f[3] - f[1]};
  const Lanes trace = f[0] + f[4] + f[8];
  const Mask nearSymmetric = (trace > 0.0) && (dot(skew, skew).sqrt() <= 0.01 * trace);
  const LaneMatrix gram = multiplyTransposed(f, f);
  Lanes distance = Lanes::Zero();
  LaneMatrix factor;
  for (std::size_t k = 0; k < 9; ++k) {
    const double diagonal = (k % 4 == 0) ? 1.0 : 0.0;
    const Lanes entry = gram[k] - diagonal;
    distance += entry * entry;
    factor[k] = (-0.5 * gram[k]) + (1.5 * diagonal);
  }
  const LaneMatrix x = select(distance < 0.25, multiply(f, factor), f);
  const LaneVector x0 = column(x, 0);
  const LaneVector x1 = column(x, 1);
  const Lanes norm0 = dot(x0, x0).sqrt();
  const LaneVector r0{x0[0] / norm0, x0[1] / norm0, x0[2] / norm0};
  const Lanes projection = dot(r0, x1);
  LaneVector r1{x1[0] - (projection * r0[0]), x1[1] - (projection * r0[1]), x1[2] - (projection * r0[2])};
  const Lanes norm1 = dot(r1, r1).sqrt();
  for (Lanes& entry : r1) entry /= norm1;
  // Columns r0, r1, r0 x r1.
  const LaneMatrix start{r0[0], r1[0], (r0[1] * r1[2]) - (r0[2] * r1[1]),
                         r0[1], r1[1], (r0[2] * r1[0]) - (r0[0] * r1[2]),
                         r0[2], r1[2], (r0[0] * r1[1]) - (r0[1] * r1[0])};
  const Mask useIdentity = nearSymmetric || !(norm0 > 0.0) || !(norm1 > 1e-8 * norm0);
  return select(useIdentity, identity(), start);
}

/// The Newton system of polarRotation() at rotation R: the gradient a = axial(B - B^T)
/// (B = R^T F), the adjugate and determinant of tr(S) I - S, S = sym(B), and whether
/// it is safely positive definite.
struct LaneSystem {
  LaneVector gradient;
  LaneMatrix adjugate;
  Lanes determinant;
  Mask positiveDefinite;
};

LaneSystem newtonSystem(const LaneMatrix& rotation, const LaneMatrix& f) {
  const LaneMatrix b = multiplyTransposed(rotation, f);
  LaneSystem system;
  system.gradient = {b[7] - b[5], b[2] - b[6], b[3] - b[1]};
  const Lanes m00 = b[4] + b[8];
  const Lanes m11 = b[0] + b[8];
  const Lanes m22 = b[0] + b[4];
  const Lanes m01 = -0.5 * (b[1] + b[3]);
  const Lanes m02 = -0.5 * (b[2] + b[6]);
  const Lanes m12 = -0.5 * (b[5] + b[7]);
  LaneMatrix& adj = system.adjugate;
  adj[0] = (m11 * m22) - (m12 * m12);
  adj[1] = (m02 * m12) - (m01 * m22);
  adj[2] = (m01 * m12) - (m02 * m11);
  adj[4] = (m00 * m22) - (m02 * m02);
  adj[5] = (m01 * m02) - (m00 * m12);
  adj[8] = (m00 * m11) - (m01 * m01);
  adj[3] = adj[1];
  adj[6] = adj[2];
  adj[7] = adj[5];
  system.determinant = (m00 * adj[0]) + (m01 * adj[1]) + (m02 * adj[2]);
  const Lanes trace = m00 + m11 + m22;
  const Lanes smallestBound = 4.0 * system.determinant / (trace * trace);
  system.positiveDefinite = (m00 > 0.0) && (adj[8] > 0.0) && (system.determinant > 0.0) &&
                            (smallestBound > (kRelativePairSumMargin * trace).max(kMinimumSingularValuePairSum));
  return system;
}

/// exp([w]x) by Rodrigues' formula, [w]x^2 = w w^T - |w|^2 I.
LaneMatrix rotationExponential(const LaneVector& w) {
  const Lanes angleSquared = dot(w, w);
  const Mask small = angleSquared < 1e-8;
  Lanes sinc = 1.0 - (angleSquared / 6.0);
  Lanes cosc = 0.5 - (angleSquared / 24.0);  // (1 - cos t) / t^2
  if (!small.all()) {
    const Lanes angle = angleSquared.sqrt();
    sinc = small.select(sinc, angle.sin() / angle);
    cosc = small.select(cosc, (1.0 - angle.cos()) / angleSquared);
  }
  LaneMatrix result;
  for (std::size_t i = 0; i < 3; ++i)
    for (std::size_t j = 0; j < 3; ++j) result[(3 * i) + j] = cosc * (w[i] * w[j]);
  for (std::size_t i = 0; i < 3; ++i) result[4 * i] += 1.0 - (cosc * angleSquared);
  result[1] -= sinc * w[2];
  result[2] += sinc * w[1];
  result[3] += sinc * w[2];
  result[5] -= sinc * w[0];
  result[6] -= sinc * w[1];
  result[7] += sinc * w[0];
  return result;
}

/// The rotations of the lanes; `settled` marks the lanes whose Newton iteration converged
/// (the others need the scalar polarRotation()), steps their Newton steps.
struct LaneRotation {
  LaneMatrix rotation;
  LaneSystem system;  // at the final rotation
  Mask settled;
  Eigen::Array<int, kElementLanes, 1> steps = Eigen::Array<int, kElementLanes, 1>::Zero();
};

/// polarRotation()'s Newton iteration on all lanes at once: each lane stops by the scalar
/// rule (gradient below the rounding floor, or a step below kConvergedStep) and keeps its
/// rotation while the others go on; a lane whose system is not positive definite, or that
/// needs more than kMaxNewtonSteps, is left unsettled.
LaneRotation newtonRotation(const LaneMatrix& f) {
  Lanes squaredNorm = Lanes::Zero();
  for (const Lanes& entry : f) squaredNorm += entry * entry;
  const Lanes gradientFloor = 8.0 * std::numeric_limits<double>::epsilon() * squaredNorm.sqrt();
  LaneRotation lanes;
  lanes.rotation = deterministicStart(f);
  lanes.system = newtonSystem(lanes.rotation, f);
  lanes.settled = Mask::Constant(false);
  Mask active = squaredNorm.isFinite();
  for (int step = 0; active.any(); ++step) {
    active = active && lanes.system.positiveDefinite;
    const Mask small = dot(lanes.system.gradient, lanes.system.gradient).sqrt() <= gradientFloor;
    lanes.settled = lanes.settled || (active && small);
    active = active && !small;
    if (step == kMaxNewtonSteps || !active.any()) break;
    const LaneSystem& system = lanes.system;
    LaneVector w;
    for (std::size_t i = 0; i < 3; ++i) {
      w[i] = ((system.adjugate[3 * i] * system.gradient[0]) + (system.adjugate[(3 * i) + 1] * system.gradient[1]) +
              (system.adjugate[(3 * i) + 2] * system.gradient[2])) /
             system.determinant;
    }
    const Lanes angle = dot(w, w).sqrt();
    for (Lanes& entry : w) entry = (angle > 1.0).select(entry / angle, entry);
    lanes.rotation = select(active, multiply(lanes.rotation, rotationExponential(w)), lanes.rotation);
    lanes.steps += active.cast<int>();
    const Mask converged = active && (angle < kConvergedStep);
    lanes.settled = lanes.settled || converged;
    active = active && !converged;
    lanes.system = newtonSystem(lanes.rotation, f);
  }
  return lanes;
}

/// Lane l of m as a matrix.
Eigen::Matrix3d laneMatrix(const LaneMatrix& m, int lane) {
  Eigen::Matrix3d out;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) out(i, j) = m[toIndex((3 * i) + j)][lane];
  return out;
}

/// F = I + sum_a u_a g_a^T of the batch's lanes.
LaneMatrix deformationGradient(const ElementBatches& batches, int batch, const Eigen::VectorXd& displacement) {
  const int* vertices = batches.vertices.data() + (toIndex(batch) * 4 * kElementLanes);
  const Lanes* g = batches.gradients.data() + (toIndex(batch) * 12);
  std::array<LaneVector, 4> u;
  for (int a = 0; a < 4; ++a)
    for (int l = 0; l < kElementLanes; ++l) {
      const double* ua = displacement.data() + (3 * static_cast<Eigen::Index>(vertices[(a * kElementLanes) + l]));
      for (std::size_t i = 0; i < 3; ++i) u[toIndex(a)][i][l] = ua[i];
    }
  LaneMatrix f;
  for (std::size_t i = 0; i < 3; ++i)
    for (std::size_t j = 0; j < 3; ++j) {
      f[(3 * i) + j] = (u[0][i] * g[j]) + (u[1][i] * g[3 + j]) + (u[2][i] * g[6 + j]) + (u[3][i] * g[9 + j]);
      if (i == j) f[(3 * i) + j] += 1.0;
    }
  return f;
}

/// V sigma for eps = sym(R^T F) - I and the energy V (mu eps:eps + lambda/2 tr(eps)^2).
LaneMatrix corotatedStressVolume(const LaneMatrix& rotation, const LaneMatrix& f, const Lanes& lambdaVolume,
                                 const Lanes& muVolume, Lanes& energy) {
  const LaneMatrix corotated = multiplyTransposed(rotation, f);
  LaneMatrix strain;
  for (std::size_t i = 0; i < 3; ++i)
    for (std::size_t j = 0; j < 3; ++j) strain[(3 * i) + j] = 0.5 * (corotated[(3 * i) + j] + corotated[(3 * j) + i]);
  for (std::size_t i = 0; i < 3; ++i) strain[4 * i] -= 1.0;
  const Lanes trace = strain[0] + strain[4] + strain[8];
  Lanes squaredNorm = Lanes::Zero();
  LaneMatrix stressVolume;
  for (std::size_t k = 0; k < 9; ++k) {
    squaredNorm += strain[k] * strain[k];
    stressVolume[k] = (2.0 * muVolume) * strain[k];
  }
  for (std::size_t i = 0; i < 3; ++i) stressVolume[4 * i] += lambdaVolume * trace;
  energy = (muVolume * squaredNorm) + (0.5 * lambdaVolume * trace * trace);
  return stressVolume;
}

/// Lane l's 3x4 product M g (M a lane matrix, g the batch's gradients).
void writeTimesGradients(const LaneMatrix& m, const Lanes* g, int lane, Eigen::Matrix<double, 3, 4>& out) {
  for (std::size_t a = 0; a < 4; ++a)
    for (std::size_t i = 0; i < 3; ++i) {
      out(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(a)) = (m[3 * i][lane] * g[3 * a][lane]) +
                                                                        (m[(3 * i) + 1][lane] * g[(3 * a) + 1][lane]) +
                                                                        (m[(3 * i) + 2][lane] * g[(3 * a) + 2][lane]);
    }
}

/// Lanes the Newton iteration left unsettled take the scalar polarRotation().
void settleByScalarPath(const LaneMatrix& f, bool withOperator, LaneRotation& lanes, LaneMatrix& differentialOperator,
                        BatchCounters& counters) {
  for (int l = 0; l < kElementLanes; ++l) {
    if (lanes.settled[l]) continue;
    const PolarRotation polar = polarRotation(laneMatrix(f, l), nullptr, withOperator);
    counters.newtonSteps += polar.newtonSteps - lanes.steps[l];  // the scalar path redoes them
    counters.fallbacks += polar.usedDecomposition ? 1 : 0;
    for (std::size_t k = 0; k < 9; ++k) {
      lanes.rotation[k][l] = polar.rotation(static_cast<Eigen::Index>(k / 3), static_cast<Eigen::Index>(k % 3));
      if (withOperator) {
        differentialOperator[k][l] =
            polar.differentialOperator(static_cast<Eigen::Index>(k / 3), static_cast<Eigen::Index>(k % 3));
      }
    }
  }
}

}  // namespace

ElementBatches makeElementBatches(const Eigen::Matrix4Xi& elements,
                                  const std::vector<Eigen::Matrix<double, 3, 4>>& shapeGradients,
                                  const std::vector<Eigen::Vector2d>& lameVolume) {
  ElementBatches batches;
  batches.numBatches = static_cast<int>(elements.cols()) / kElementLanes;
  const std::size_t count = toIndex(batches.numBatches);
  batches.vertices.resize(count * 4 * kElementLanes);
  batches.gradients.resize(count * 12);
  batches.lameVolume.resize(count * 2);
  for (std::size_t k = 0; k < count; ++k) {
    for (int l = 0; l < kElementLanes; ++l) {
      const std::size_t e = (k * kElementLanes) + toIndex(l);
      for (int a = 0; a < 4; ++a) {
        batches.vertices[(k * 4 * kElementLanes) + toIndex((a * kElementLanes) + l)] =
            elements(a, static_cast<Eigen::Index>(e));
        for (int j = 0; j < 3; ++j) batches.gradients[(k * 12) + toIndex((3 * a) + j)][l] = shapeGradients[e](j, a);
      }
      batches.lameVolume[2 * k][l] = lameVolume[e][0];
      batches.lameVolume[(2 * k) + 1][l] = lameVolume[e][1];
    }
  }
  return batches;
}

void evaluateBatch(const ElementBatches& batches, int batch, const Eigen::VectorXd& displacement,
                   const BatchOutputs& outputs, BatchCounters& counters) {
  const LaneMatrix f = deformationGradient(batches, batch, displacement);
  LaneRotation lanes = newtonRotation(f);
  const bool withOperator = outputs.differentialOperators != nullptr;
  LaneMatrix differentialOperator;
  if (withOperator) {
    for (std::size_t k = 0; k < 9; ++k) differentialOperator[k] = lanes.system.adjugate[k] / lanes.system.determinant;
  }
  counters.newtonSteps += lanes.steps.sum();
  if (!lanes.settled.all()) settleByScalarPath(f, withOperator, lanes, differentialOperator, counters);
  const LaneMatrix& rotation = lanes.rotation;
  Lanes energy;
  const LaneMatrix stressVolume = corotatedStressVolume(rotation, f, batches.lameVolume[2 * toIndex(batch)],
                                                        batches.lameVolume[(2 * toIndex(batch)) + 1], energy);
  const LaneMatrix rotatedStress = multiply(rotation, stressVolume);
  const Lanes* g = batches.gradients.data() + (toIndex(batch) * 12);
  for (int l = 0; l < kElementLanes; ++l) {
    const std::size_t e = (toIndex(batch) * kElementLanes) + toIndex(l);
    outputs.rotations[e] = laneMatrix(rotation, l);
    if (withOperator) outputs.differentialOperators[e] = laneMatrix(differentialOperator, l);
    outputs.energies[e] = energy[l];
    writeTimesGradients(rotatedStress, g, l, outputs.forces[e]);
    writeTimesGradients(rotation, g, l, outputs.rotatedGradients[e]);
  }
}

}  // namespace asyncfem::detail
