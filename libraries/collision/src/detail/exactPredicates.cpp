// SPDX-License-Identifier: BSD-3-Clause
#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <detail/exactPredicates.hpp>
#include <vector>

namespace asyncfem::detail {

namespace {

// The floating-point determinant is trusted when its magnitude exceeds this multiple of
// the sum of the magnitudes of its terms (the permanent). Its rounding error is at most
// about 8 unit round-offs (7.8e-16) of the permanent for the 3 x 3 case and 3.3e-16 for the
// 2 x 2 case; 1e-14 leaves a margin of ten for the rounding of the permanent itself.
constexpr double kFilter = 1e-14;

/// A number held exactly as high + low (high = fl(high + low)).
struct TwoTerm {
  double high;
  double low;
};

/// a - b exactly as a two-term value (Knuth's two-sum on a and -b).
TwoTerm exactDifference(double a, double b) {
  const double high = a - b;
  const double bVirtual = a - high;
  const double aVirtual = high + bVirtual;
  return {high, (a - aVirtual) + (bVirtual - b)};
}

/// A sum of doubles held exactly as non-overlapping components of increasing magnitude; its
/// sign is the sign of its largest non-zero component.
class ExactSum {
 public:
  void add(double value) {
    // Adds value to every component in turn, keeping each rounding error as a component
    // (two-sum is exact), so that the components still sum to the exact total.
    double carry = value;
    std::size_t kept = 0;
    for (const double component : components_) {
      const double sum = carry + component;
      const double componentVirtual = sum - carry;
      const double carryVirtual = sum - componentVirtual;
      const double error = (carry - carryVirtual) + (component - componentVirtual);
      if (error != 0.0) components_[kept++] = error;
      carry = sum;
    }
    components_.resize(kept);
    if (carry != 0.0) components_.push_back(carry);
  }
  /// Adds x * y * z exactly (four doubles: the product's rounding errors via fma).
  void addProduct(double x, double y, double z) {
    const double xy = x * y;
    const double xyError = std::fma(x, y, -xy);
    const double high = xy * z;
    const double low = xyError * z;
    add(high);
    add(std::fma(xy, z, -high));
    add(low);
    add(std::fma(xyError, z, -low));
  }
  void addProduct(double x, double y) {
    const double xy = x * y;
    add(xy);
    add(std::fma(x, y, -xy));
  }
  int sign() const {
    if (components_.empty()) return 0;
    return components_.back() > 0.0 ? 1 : -1;
  }

 private:
  std::vector<double> components_;
};

int signOf(double value) { return value > 0.0 ? 1 : (value < 0.0 ? -1 : 0); }

}  // namespace

int orientation2d(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  const double left = (b.x() - a.x()) * (c.y() - a.y());
  const double right = (b.y() - a.y()) * (c.x() - a.x());
  const double determinant = left - right;
  if (std::abs(determinant) > kFilter * (std::abs(left) + std::abs(right))) return signOf(determinant);
  // Exact: each difference is a two-term value, each product of two of them four products
  // of doubles.
  const std::array<TwoTerm, 2> u{exactDifference(b.x(), a.x()), exactDifference(b.y(), a.y())};
  const std::array<TwoTerm, 2> v{exactDifference(c.x(), a.x()), exactDifference(c.y(), a.y())};
  ExactSum sum;
  for (const double p : {u[0].high, u[0].low})
    for (const double q : {v[1].high, v[1].low}) sum.addProduct(p, q);
  for (const double p : {u[1].high, u[1].low})
    for (const double q : {v[0].high, v[0].low}) sum.addProduct(-p, q);
  return sum.sign();
}

int orientation3d(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                  const Eigen::Vector3d& d) {
  const Eigen::Vector3d u = b - a, v = c - a, w = d - a;
  const double determinant = u.dot(v.cross(w));
  const double permanent = u.cwiseAbs().dot(Eigen::Vector3d(std::abs(v.y() * w.z()) + std::abs(v.z() * w.y()),
                                                            std::abs(v.z() * w.x()) + std::abs(v.x() * w.z()),
                                                            std::abs(v.x() * w.y()) + std::abs(v.y() * w.x())));
  if (std::abs(determinant) > kFilter * permanent) return signOf(determinant);
  // Exact: det of the 3 x 3 matrix of two-term differences, expanded over the six
  // permutations (Leibniz), each a sum of eight products of three doubles.
  std::array<std::array<TwoTerm, 3>, 3> m{};
  for (int i = 0; i < 3; ++i) {
    m[0][static_cast<std::size_t>(i)] = exactDifference(b[i], a[i]);
    m[1][static_cast<std::size_t>(i)] = exactDifference(c[i], a[i]);
    m[2][static_cast<std::size_t>(i)] = exactDifference(d[i], a[i]);
  }
  constexpr std::array<std::array<std::size_t, 3>, 6> kPermutations{
      {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}, {0, 2, 1}, {2, 1, 0}, {1, 0, 2}}};
  ExactSum sum;
  for (std::size_t p = 0; p < kPermutations.size(); ++p) {
    const double sign = p < 3 ? 1.0 : -1.0;
    const auto& column = kPermutations[p];
    for (const double x : {m[0][column[0]].high, m[0][column[0]].low})
      for (const double y : {m[1][column[1]].high, m[1][column[1]].low})
        for (const double z : {m[2][column[2]].high, m[2][column[2]].low}) sum.addProduct(sign * x, y, z);
  }
  return sum.sign();
}

}  // namespace asyncfem::detail
