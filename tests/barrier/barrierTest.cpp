// SPDX-License-Identifier: BSD-3-Clause
// The log barrier and the pair energies of docs/barrier-contact.md (Eqs. B1-B4): values at
// their defining points, and every gradient and Hessian against central differences.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <asyncfem/barrier/barrier.hpp>
#include <cmath>
#include <functional>
#include <random>

namespace asyncfem {
namespace {

using Vector12 = Eigen::Matrix<double, 12, 1>;
using Matrix12 = Eigen::Matrix<double, 12, 12>;
using PairEnergy = std::function<SquaredDistance(const Vector12&)>;

Eigen::Vector3d point(const Vector12& x, int k) { return x.segment<3>(3 * k); }

// Central differences of the energy's value (for the gradient) and of its gradient (for
// the Hessian), step h; returns the largest errors relative to the largest entry.
void checkDerivatives(const PairEnergy& energy, const Vector12& x, double h, double gradientTolerance,
                      double hessianTolerance) {
  const SquaredDistance at = energy(x);
  Vector12 gradient;
  Matrix12 hessian;
  for (int i = 0; i < 12; ++i) {
    Vector12 plus = x, minus = x;
    plus[i] += h;
    minus[i] -= h;
    const SquaredDistance up = energy(plus), down = energy(minus);
    gradient[i] = (up.value - down.value) / (2.0 * h);
    hessian.col(i) = (up.gradient - down.gradient) / (2.0 * h);
  }
  const double gradientScale = std::max(at.gradient.cwiseAbs().maxCoeff(), 1e-300);
  const double hessianScale = std::max(at.hessian.cwiseAbs().maxCoeff(), 1e-300);
  EXPECT_LT((gradient - at.gradient).cwiseAbs().maxCoeff() / gradientScale, gradientTolerance);
  EXPECT_LT((hessian - at.hessian).cwiseAbs().maxCoeff() / hessianScale, hessianTolerance);
  EXPECT_LT((at.hessian - at.hessian.transpose()).cwiseAbs().maxCoeff() / hessianScale, 1e-12);
}

// b(s) = -(s - sHat)^2 ln(s / sHat): zero with a zero slope at sHat (a C1 switch-on),
// unbounded at 0, positive and decreasing in between; b' and b'' against central
// differences (relative 1e-7: a step of 1e-6 s on a smooth function).
TEST(LogBarrier, ValuesAndDerivatives) {
  const double sHat = 1e-2;
  EXPECT_EQ(logBarrier(sHat, sHat).value, 0.0);
  EXPECT_EQ(logBarrier(2.0 * sHat, sHat).first, 0.0);
  EXPECT_LT(logBarrier(sHat * (1.0 - 1e-6), sHat).value, 1e-15);
  EXPECT_LT(std::abs(logBarrier(sHat * (1.0 - 1e-6), sHat).first), 1e-9);
  EXPECT_TRUE(std::isinf(logBarrier(0.0, sHat).value));
  EXPECT_TRUE(std::isnan(logBarrier(-1e-9, sHat).first));
  double previous = std::numeric_limits<double>::infinity();
  for (const double s : {1e-8, 1e-6, 1e-4, 3e-3, 9e-3}) {
    const BarrierDerivatives b = logBarrier(s, sHat);
    EXPECT_GT(b.value, 0.0);
    EXPECT_LT(b.value, previous);
    previous = b.value;
    EXPECT_LT(b.first, 0.0);
    EXPECT_GT(b.second, 0.0);  // convex on (0, sHat)
    const double h = 1e-6 * s;
    const BarrierDerivatives up = logBarrier(s + h, sHat), down = logBarrier(s - h, sHat);
    EXPECT_NEAR((up.value - down.value) / (2.0 * h), b.first, 1e-7 * std::abs(b.first)) << s;
    EXPECT_NEAR((up.first - down.first) / (2.0 * h), b.second, 1e-7 * std::abs(b.second)) << s;
  }
}

// |e0 x e1|^2 against its definition and central differences, and zero for parallel edges.
TEST(EdgeCrossSquared, DefinitionAndDerivatives) {
  std::mt19937 random(3);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  for (int trial = 0; trial < 10; ++trial) {
    Vector12 x;
    for (int i = 0; i < 12; ++i) x[i] = uniform(random);
    const SquaredDistance c = edgeCrossSquared(point(x, 0), point(x, 1), point(x, 2), point(x, 3));
    const Eigen::Vector3d cross = (point(x, 1) - point(x, 0)).cross(point(x, 3) - point(x, 2));
    EXPECT_NEAR(c.value, cross.squaredNorm(), 1e-14);
    // A quartic polynomial: central differences are exact up to h^2 times its fourth
    // derivative's scale, 1e-8 relative at h = 1e-4 (and round-off).
    checkDerivatives(
        [](const Vector12& y) { return edgeCrossSquared(point(y, 0), point(y, 1), point(y, 2), point(y, 3)); }, x, 1e-4,
        1e-7, 1e-7);
  }
  const Eigen::Vector3d a0(0, 0, 0), a1(1, 2, 3), b0(5, -1, 2);
  EXPECT_NEAR(edgeCrossSquared(a0, a1, b0, b0 + 0.5 * (a1 - a0)).value, 0.0, 1e-14);
}

// The point-triangle barrier in the face, edge and vertex regions (away from the regions'
// borders, where the distance's Hessian jumps): gradient and Hessian against central
// differences (step 1e-7 on distances ~1e-2: relative 1e-5 for the gradient, 1e-4 for the
// Hessian, which differences the gradient); zero beyond sHat.
TEST(PairBarrier, PointTriangleDerivativesInEveryRegion) {
  const Eigen::Vector3d a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  const double sHat = 0.04;                                       // dhat 0.2
  const std::vector<Eigen::Vector3d> points{{0.3, 0.2, 0.1},      // over the face
                                            {0.5, -0.08, 0.05},   // beside edge ab
                                            {-0.07, -0.06, 0.1},  // beyond vertex a
                                            {0.6, 0.6, 0.05}};    // beside edge bc
  for (const Eigen::Vector3d& p : points) {
    Vector12 x;
    x << p, a, b, c;
    const PairEnergy energy = [sHat](const Vector12& y) {
      return pointTriangleBarrier(point(y, 0), point(y, 1), point(y, 2), point(y, 3), sHat);
    };
    EXPECT_GT(energy(x).value, 0.0);
    checkDerivatives(energy, x, 1e-7, 1e-5, 1e-4);
  }
  Vector12 far;
  far << Eigen::Vector3d(0.3, 0.2, 0.5), a, b, c;
  EXPECT_EQ(pointTriangleBarrier(point(far, 0), a, b, c, sHat).value, 0.0);
  EXPECT_EQ(pointTriangleBarrier(point(far, 0), a, b, c, sHat).gradient.norm(), 0.0);
}

// The edge-edge barrier, crossing edges (mollifier off) and nearly parallel ones (mollifier
// on: x below epsX): derivatives against central differences as above; the mollified energy
// goes to zero as the edges turn parallel (the barrier alone does not).
TEST(PairBarrier, EdgeEdgeDerivativesWithAndWithoutTheMollifier) {
  const double sHat = 0.04;
  const Eigen::Vector3d a0(0, 0, 0), a1(1, 0, 0);
  struct Case {
    Eigen::Vector3d b0, b1;
    bool mollified;
  };
  const std::vector<Case> cases{{{0.4, -0.5, 0.1}, {0.6, 0.5, 0.12}, false},
                                {{0.2, 0.1, 0.01}, {0.9, 0.1 + 0.01, 0.012}, true}};
  for (const Case& k : cases) {
    const double epsX = mollifierThreshold(a0, a1, k.b0, k.b1);
    EXPECT_EQ(edgeCrossSquared(a0, a1, k.b0, k.b1).value < epsX, k.mollified);
    Vector12 x;
    x << a0, a1, k.b0, k.b1;
    const PairEnergy energy = [sHat, epsX](const Vector12& y) {
      return edgeEdgeBarrier(point(y, 0), point(y, 1), point(y, 2), point(y, 3), sHat, epsX);
    };
    EXPECT_GT(energy(x).value, 0.0);
    checkDerivatives(energy, x, 1e-7, 1e-5, 1e-4);
  }
  const Eigen::Vector3d b0(0.2, 0.1, 0.0);
  const double epsX = mollifierThreshold(a0, a1, b0, b0 + Eigen::Vector3d(0.7, 0, 0));
  EXPECT_NEAR(edgeEdgeBarrier(a0, a1, b0, b0 + Eigen::Vector3d(0.7, 0, 0), sHat, epsX).value, 0.0, 1e-15);
  EXPECT_GT(edgeEdgeBarrier(a0, a1, b0, b0 + Eigen::Vector3d(0.7, 0.05, 0), sHat, epsX).value, 0.0);
}

// The projection: positive semi-definite (eigenvalues >= -1e-12 of the largest), equal to
// the input where it already is, and only the negative part removed (H - P(H) has the
// negative eigenvalues' span: P(H) - H is positive semi-definite).
TEST(PairBarrier, ProjectionKeepsThePositivePart) {
  std::mt19937 random(5);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  Matrix12 a;
  for (int i = 0; i < 144; ++i) a.data()[i] = uniform(random);
  const Matrix12 indefinite = a + a.transpose();
  const Matrix12 projected = projectToPositiveSemiDefinite(indefinite);
  const double scale = indefinite.cwiseAbs().maxCoeff();
  const Eigen::SelfAdjointEigenSolver<Matrix12> before(indefinite), after(projected), added(projected - indefinite);
  EXPECT_LT(before.eigenvalues().minCoeff(), 0.0);
  EXPECT_GT(after.eigenvalues().minCoeff(), -1e-12 * scale);
  EXPECT_GT(added.eigenvalues().minCoeff(), -1e-12 * scale);
  const Matrix12 definite = a * a.transpose();
  EXPECT_LT((projectToPositiveSemiDefinite(definite) - definite).cwiseAbs().maxCoeff(),
            1e-12 * definite.cwiseAbs().maxCoeff());
}

}  // namespace
}  // namespace asyncfem
