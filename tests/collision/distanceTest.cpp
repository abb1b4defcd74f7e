// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <algorithm>
#include <asyncfem/collision/distance.hpp>
#include <cmath>
#include <functional>
#include <random>

namespace asyncfem {
namespace {

using Vector3 = Eigen::Vector3d;
using Vector12 = Eigen::Matrix<double, 12, 1>;

/// Oracle: the minimum of a squared distance |x(s, t)|^2 over a parameter domain, by dense
/// sampling (a 101 x 101 grid) and then 40 rounds of zooming on the best sample (an 11 x 11
/// grid over +-2 spacings, shrinking 5 times per round). Every value it returns is the
/// squared distance of a feasible pair of points, so the exact minimum is never above it.
double sampledMinimum(const std::function<double(double, double)>& squaredDistance,
                      const std::function<bool(double, double)>& feasible) {
  double best = std::numeric_limits<double>::infinity();
  double bestS = 0.0, bestT = 0.0;
  auto sample = [&](double s0, double t0, double spacing, int count) {
    double roundBestS = bestS, roundBestT = bestT;
    for (int i = -count; i <= count; ++i) {
      for (int j = -count; j <= count; ++j) {
        const double s = std::clamp(s0 + i * spacing, 0.0, 1.0);
        const double t = std::clamp(t0 + j * spacing, 0.0, 1.0);
        if (!feasible(s, t)) continue;
        const double d = squaredDistance(s, t);
        if (d < best) {
          best = d;
          roundBestS = s;
          roundBestT = t;
        }
      }
    }
    bestS = roundBestS;
    bestT = roundBestT;
  };
  sample(0.5, 0.5, 0.01, 50);
  double spacing = 0.01;
  for (int round = 0; round < 40; ++round) {
    sample(bestS, bestT, spacing / 5.0, 10);
    spacing /= 5.0;
  }
  return best;
}

double pointTriangleOracle(const Vector3& p, const Vector3& a, const Vector3& b, const Vector3& c) {
  return sampledMinimum([&](double s, double t) { return (p - (a + s * (b - a) + t * (c - a))).squaredNorm(); },
                        [](double s, double t) { return s + t <= 1.0; });
}

double edgeEdgeOracle(const Vector3& a0, const Vector3& a1, const Vector3& b0, const Vector3& b1) {
  return sampledMinimum([&](double s, double t) { return (a0 + s * (a1 - a0) - b0 - t * (b1 - b0)).squaredNorm(); },
                        [](double, double) { return true; });
}

/// The exact minimum is below every sample of the oracle (up to the round-off of one
/// evaluation, 1e-14 of the squared scale), and the oracle's zooming reaches the minimum to
/// 1e-12 of the squared scale (measured: within 1e-14 on these cases; the margin covers a
/// zoom that crawls along the long valley of nearly parallel edges).
void expectMatchesOracle(double exact, double oracle, double scaleSquared) {
  EXPECT_LE(exact, oracle + 1e-14 * scaleSquared);
  EXPECT_GE(exact, oracle - 1e-12 * scaleSquared);
}

struct RandomPoints {
  std::mt19937 generator{20261207};
  std::uniform_real_distribution<double> uniform{-1.0, 1.0};
  Vector3 next() { return {uniform(generator), uniform(generator), uniform(generator)}; }
};

/// Compares value(x), full(x).value and the oracle on 300 random configurations in [-1, 1]^3
/// (squared scale 16) and checks that each of the three kinds of closed form was drawn
/// more than 10 times, so that every form was compared.
template <typename Value, typename Full, typename Region, typename Oracle>
void expectRandomConfigurationsMatchOracle(Value value, Full full, Region region, Oracle oracle) {
  RandomPoints random;
  std::array<int, 4> kinds{};
  for (int trial = 0; trial < 300; ++trial) {
    const Vector3 x0 = random.next(), x1 = random.next(), x2 = random.next(), x3 = random.next();
    const double exact = value(x0, x1, x2, x3);
    expectMatchesOracle(exact, oracle(x0, x1, x2, x3), 16.0);
    EXPECT_DOUBLE_EQ(full(x0, x1, x2, x3).value, exact);
    ++kinds[static_cast<std::size_t>(distanceKind(region(x0, x1, x2, x3)))];
  }
  EXPECT_GT(kinds[static_cast<std::size_t>(DistanceKind::PointPoint)], 10);
  EXPECT_GT(kinds[static_cast<std::size_t>(DistanceKind::PointEdge)], 10);
  EXPECT_GT(kinds[static_cast<std::size_t>(DistanceKind::PointPlane)] +
                kinds[static_cast<std::size_t>(DistanceKind::LineLine)],
            10);
}

TEST(PointTriangleDistance, MatchesSampledMinimumOnRandomConfigurations) {
  expectRandomConfigurationsMatchOracle(
      pointTriangleDistanceSquared,
      [](const Vector3& p, const Vector3& a, const Vector3& b, const Vector3& c) {
        return pointTriangleDistance(p, a, b, c);
      },
      pointTriangleRegion, pointTriangleOracle);
}

TEST(EdgeEdgeDistance, MatchesSampledMinimumOnRandomConfigurations) {
  expectRandomConfigurationsMatchOracle(
      edgeEdgeDistanceSquared,
      [](const Vector3& a0, const Vector3& a1, const Vector3& b0, const Vector3& b1) {
        return edgeEdgeDistance(a0, a1, b0, b1);
      },
      edgeEdgeRegion, edgeEdgeOracle);
}

TEST(PointTriangleDistance, DegenerateConfigurationsHaveTheirClosedFormValues) {
  const Vector3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  struct Case {
    Vector3 p;
    double expected;
    PointTriangleRegion region;
  };
  const Case cases[] = {
      {{0.2, 0.2, 0.5}, 0.25, PointTriangleRegion::Face},       // over the face
      {{0.2, 0.2, 0.0}, 0.0, PointTriangleRegion::Face},        // in the face
      {{0.5, 0.0, 0.3}, 0.09, PointTriangleRegion::Face},       // exactly over edge AB: face and edge agree
      {{0.5, -0.4, 0.3}, 0.25, PointTriangleRegion::EdgeAB},    // beside edge AB
      {{0.5, -0.4, 0.0}, 0.16, PointTriangleRegion::EdgeAB},    // coplanar, beside edge AB
      {{1.0, 1.0, 0.0}, 0.5, PointTriangleRegion::EdgeBC},      // coplanar, beside the hypotenuse
      {{-0.4, 0.5, 0.0}, 0.16, PointTriangleRegion::EdgeCA},    // coplanar, beside edge CA
      {{0.0, 0.0, 0.7}, 0.49, PointTriangleRegion::Face},       // exactly over vertex A
      {{-0.3, -0.4, 0.0}, 0.25, PointTriangleRegion::VertexA},  // coplanar, beyond vertex A
      {{2.0, -1.0, 1.0}, 3.0, PointTriangleRegion::VertexB},    // beyond vertex B
      {{-0.5, 2.0, 0.0}, 1.25, PointTriangleRegion::VertexC},   // coplanar, beyond vertex C
  };
  for (const Case& test : cases) {
    EXPECT_NEAR(pointTriangleDistanceSquared(test.p, a, b, c), test.expected, 1e-15) << test.p.transpose();
    EXPECT_EQ(pointTriangleRegion(test.p, a, b, c), test.region) << test.p.transpose();
    EXPECT_NEAR(pointTriangleOracle(test.p, a, b, c), test.expected, 1e-10) << test.p.transpose();
  }
  // A zero-area triangle is its edges: (a, b, b + (b - a)) is the segment from a to 2b.
  EXPECT_NEAR(pointTriangleDistanceSquared({1.5, 0.5, 0.0}, a, b, 2.0 * b), 0.25, 1e-15);
  EXPECT_EQ(distanceKind(pointTriangleRegion({1.5, 0.5, 0.0}, a, b, 2.0 * b)), DistanceKind::PointEdge);
}

TEST(EdgeEdgeDistance, ParallelAndDegenerateEdges) {
  const Vector3 a0(0, 0, 0), a1(1, 0, 0);
  struct Case {
    Vector3 b0, b1;
    double expected;
  };
  const Case cases[] = {
      {{0.2, 0.3, 0.0}, {0.8, 0.3, 0.0}, 0.09},    // parallel, overlapping
      {{0.8, 0.3, 0.0}, {0.2, 0.3, 0.0}, 0.09},    // antiparallel, overlapping
      {{1.5, 0.0, 0.4}, {2.5, 0.0, 0.4}, 0.41},    // parallel, apart along the line
      {{2.0, 0.0, 0.0}, {3.0, 0.0, 0.0}, 1.0},     // collinear, apart
      {{0.5, 0.0, 0.0}, {3.0, 0.0, 0.0}, 0.0},     // collinear, overlapping
      {{0.5, -1.0, 0.0}, {0.5, 1.0, 0.0}, 0.0},    // crossing
      {{0.5, -1.0, 0.2}, {0.5, 1.0, 0.2}, 0.04},   // skew, over each other's inside
      {{1.0, 0.0, 0.3}, {1.0, 1.0, 0.3}, 0.09},    // over endpoint a1 exactly
      {{0.3, 0.5, 0.0}, {0.3, 0.5, 0.0}, 0.25},    // zero-length edge b
      {{0.5, 1e-9, 1.0}, {1.5, -1e-9, 1.0}, 1.0},  // nearly parallel (sin^2 ~ 1e-18)
  };
  for (const Case& test : cases) {
    const double exact = edgeEdgeDistanceSquared(a0, a1, test.b0, test.b1);
    EXPECT_NEAR(exact, test.expected, 1e-14) << test.b0.transpose() << " / " << test.b1.transpose();
    expectMatchesOracle(exact, edgeEdgeOracle(a0, a1, test.b0, test.b1), 4.0);
    // Symmetric under swapping the edges and reversing them.
    EXPECT_NEAR(edgeEdgeDistanceSquared(test.b1, test.b0, a1, a0), exact, 1e-14);
  }
  EXPECT_EQ(edgeEdgeRegion(a0, a1, {0.5, -1.0, 0.2}, {0.5, 1.0, 0.2}), EdgeEdgeRegion::Interior);
  EXPECT_EQ(distanceKind(edgeEdgeRegion(a0, a1, {0.2, 0.3, 0.0}, {0.8, 0.3, 0.0})), DistanceKind::PointEdge);
  EXPECT_EQ(edgeEdgeRegion(a0, a1, {2.0, 0.0, 0.0}, {3.0, 0.0, 0.0}), EdgeEdgeRegion::A1B0);
}

/// Central differences of value and gradient in each of the 12 coordinates with step
/// h = 1e-6 on configurations of size ~1: the truncation error is ~h^2 |third derivative|
/// ~ 1e-12 and the round-off ~eps |f| / h ~ 1e-10, so a relative tolerance of 1e-6 (of
/// max(1, |derivative|)) leaves four orders of margin, while a wrong term in a closed form
/// (a sign, a missing factor 2) gives an error of order 1.
template <typename Evaluate>
void expectDerivativesMatchFiniteDifferences(const Vector12& x, Evaluate evaluate) {
  constexpr double kStep = 1e-6;
  constexpr double kTolerance = 1e-6;
  const SquaredDistance at = evaluate(x);
  Vector12 gradient;
  Eigen::Matrix<double, 12, 12> hessian;
  for (int i = 0; i < 12; ++i) {
    Vector12 forward = x, backward = x;
    forward[i] += kStep;
    backward[i] -= kStep;
    const SquaredDistance f = evaluate(forward), b = evaluate(backward);
    gradient[i] = (f.value - b.value) / (2.0 * kStep);
    hessian.col(i) = (f.gradient - b.gradient) / (2.0 * kStep);
  }
  EXPECT_LE((gradient - at.gradient).norm(), kTolerance * std::max(1.0, at.gradient.norm()));
  EXPECT_LE((hessian - at.hessian).norm(), kTolerance * std::max(1.0, at.hessian.norm()));
  EXPECT_LE((at.hessian - at.hessian.transpose()).norm(), 1e-12 * std::max(1.0, at.hessian.norm()));
}

Vector12 stack(const Vector3& p0, const Vector3& p1, const Vector3& p2, const Vector3& p3) {
  Vector12 x;
  x << p0, p1, p2, p3;
  return x;
}

TEST(PointTriangleDistance, DerivativesMatchFiniteDifferencesInEveryRegion) {
  RandomPoints random;
  std::array<int, 7> seen{};
  for (int trial = 0; trial < 200; ++trial) {
    const Vector12 x = stack(random.next(), random.next(), random.next(), random.next());
    const PointTriangleRegion region =
        pointTriangleRegion(x.segment<3>(0), x.segment<3>(3), x.segment<3>(6), x.segment<3>(9));
    ++seen[static_cast<std::size_t>(region)];
    // The region is held fixed: the derivatives are those of one closed form.
    expectDerivativesMatchFiniteDifferences(x, [region](const Vector12& y) {
      return pointTriangleDistance(y.segment<3>(0), y.segment<3>(3), y.segment<3>(6), y.segment<3>(9), region);
    });
  }
  for (std::size_t r = 0; r < seen.size(); ++r) EXPECT_GT(seen[r], 0) << "region " << r << " never drawn";
}

TEST(EdgeEdgeDistance, DerivativesMatchFiniteDifferencesInEveryRegion) {
  RandomPoints random;
  std::array<int, 9> seen{};
  for (int trial = 0; trial < 400; ++trial) {
    const Vector12 x = stack(random.next(), random.next(), random.next(), random.next());
    const EdgeEdgeRegion region = edgeEdgeRegion(x.segment<3>(0), x.segment<3>(3), x.segment<3>(6), x.segment<3>(9));
    ++seen[static_cast<std::size_t>(region)];
    expectDerivativesMatchFiniteDifferences(x, [region](const Vector12& y) {
      return edgeEdgeDistance(y.segment<3>(0), y.segment<3>(3), y.segment<3>(6), y.segment<3>(9), region);
    });
  }
  for (std::size_t r = 0; r < seen.size(); ++r) EXPECT_GT(seen[r], 0) << "region " << r << " never drawn";
}

TEST(EdgeEdgeDistance, FiniteDifferenceCheckDetectsAWrongHessian) {
  // Negative control: the check above fails for a Hessian off by a small symmetric term.
  const Vector12 x = stack({0, 0, 0}, {1, 0, 0}, {0.5, -1, 0.3}, {0.4, 1, 0.5});
  const EdgeEdgeRegion region = edgeEdgeRegion(x.segment<3>(0), x.segment<3>(3), x.segment<3>(6), x.segment<3>(9));
  ASSERT_EQ(region, EdgeEdgeRegion::Interior);
  const SquaredDistance at =
      edgeEdgeDistance(x.segment<3>(0), x.segment<3>(3), x.segment<3>(6), x.segment<3>(9), region);
  Eigen::Matrix<double, 12, 12> fd;
  for (int i = 0; i < 12; ++i) {
    Vector12 f = x, b = x;
    f[i] += 1e-6;
    b[i] -= 1e-6;
    fd.col(i) =
        (edgeEdgeDistance(f.segment<3>(0), f.segment<3>(3), f.segment<3>(6), f.segment<3>(9), region).gradient -
         edgeEdgeDistance(b.segment<3>(0), b.segment<3>(3), b.segment<3>(6), b.segment<3>(9), region).gradient) /
        2e-6;
  }
  Eigen::Matrix<double, 12, 12> wrong = at.hessian;
  wrong(0, 6) += 1e-3;
  wrong(6, 0) += 1e-3;
  EXPECT_LE((fd - at.hessian).norm(), 1e-6 * at.hessian.norm());
  EXPECT_GT((fd - wrong).norm(), 1e-6 * at.hessian.norm());
}

}  // namespace
}  // namespace asyncfem
