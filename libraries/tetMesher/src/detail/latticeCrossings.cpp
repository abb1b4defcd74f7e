// SPDX-License-Identifier: BSD-3-Clause
#include "detail/latticeCrossings.hpp"

#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include "detail/bccLattice.hpp"
#include "detail/gradedLattice.hpp"

namespace asyncfem::detail {

namespace {

/// Root of f on the segment from x0 (value f0) to x1 (value f1), f0 f1 < 0, by the
/// Illinois variant of regula falsi; returns the parameter t in (0, 1).
double findRoot(const ImplicitFunction& f, const Eigen::Vector3d& x0, const Eigen::Vector3d& x1, double f0, double f1,
                int iterations) {
  double t0 = 0.0, t1 = 1.0;
  int lastSide = 0;
  double t = f0 / (f0 - f1);
  for (int it = 0; it < iterations && t1 - t0 > 1e-12; ++it) {
    t = (t0 * f1 - t1 * f0) / (f1 - f0);
    if (!(t > t0 && t < t1)) t = 0.5 * (t0 + t1);
    const double ft = f(x0 + t * (x1 - x0));
    if (ft == 0.0) return t;
    if ((ft < 0.0) == (f0 < 0.0)) {
      t0 = t;
      f0 = ft;
      if (lastSide == -1) f1 *= 0.5;
      lastSide = -1;
    } else {
      t1 = t;
      f1 = ft;
      if (lastSide == 1) f0 *= 0.5;
      lastSide = 1;
    }
  }
  return t;
}

/// Step 3 of the method: for each lattice vertex, the closest cut point on one of its edges
/// that lies within alpha times the edge's length of it (the first one offered on a tie).
class WarpFinder {
 public:
  /// A cut point at parameter t of lattice edge (u, v) of the given length.
  void addCut(long long u, long long v, double t, const Eigen::Vector3d& point, double length, double alpha) {
    consider(u, t * length, alpha * length, point);
    consider(v, (1.0 - t) * length, alpha * length, point);
  }
  /// Moves every violating vertex onto its cut point, which makes it a surface vertex.
  std::unordered_map<long long, Eigen::Vector3d> warp(std::vector<int>& signs) const {
    std::unordered_map<long long, Eigen::Vector3d> warped;
    warped.reserve(violations_.size());
    for (const auto& [v, violation] : violations_) {
      warped.emplace(v, violation.point);
      signs[static_cast<std::size_t>(v)] = 0;
    }
    return warped;
  }

 private:
  struct Violation {
    double distance;
    Eigen::Vector3d point;
  };
  void consider(long long w, double distance, double limit, const Eigen::Vector3d& point) {
    if (distance >= limit) return;
    const auto [it, inserted] = violations_.try_emplace(w, Violation{distance, point});
    if (!inserted && distance < it->second.distance) it->second = Violation{distance, point};
  }
  std::unordered_map<long long, Violation> violations_;
};

template <StuffingLattice Lattice>
std::vector<double> findCutParameters(const ImplicitFunction& f, const Lattice& lattice,
                                      const std::vector<LatticeEdge>& edges, const std::vector<double>& values,
                                      const MesherOptions& options) {
  std::vector<double> parameters(edges.size());
  const long long numEdges = static_cast<long long>(edges.size());
#pragma omp parallel for schedule(dynamic, 64) if (options.parallel)
  for (long long e = 0; e < numEdges; ++e) {
    const auto [u, v] = edges[static_cast<std::size_t>(e)];
    parameters[static_cast<std::size_t>(e)] =
        findRoot(f, lattice.position(u), lattice.position(v), values[static_cast<std::size_t>(u)],
                 values[static_cast<std::size_t>(v)], options.cutPointIterations);
  }
  return parameters;
}

}  // namespace

void checkLatticeSize(long long numVertices, const MesherOptions& options) {
  const long long limit = std::min<long long>(options.maxLatticeVertices, std::numeric_limits<std::int32_t>::max());
  if (numVertices > limit) {
    throw ValidationError("stuffIsosurface: the lattice would have " + std::to_string(numVertices) +
                          " vertices (limit " + std::to_string(limit) + "); use a larger spacing");
  }
}

template <StuffingLattice Lattice>
std::vector<double> sampleLattice(const ImplicitFunction& f, const Lattice& lattice, bool parallel,
                                  const KnownValue& known) {
  const long long numVertices = lattice.numVertices();
  std::vector<double> values(static_cast<std::size_t>(numVertices));
  bool nonFinite = false;
#pragma omp parallel for schedule(dynamic, 4096) if (parallel) reduction(|| : nonFinite)
  for (long long v = 0; v < numVertices; ++v) {
    double value = 0.0;
    if (!known || !known(v, value)) value = f(lattice.position(v));
    values[static_cast<std::size_t>(v)] = value;
    if (!std::isfinite(value)) nonFinite = true;
  }
  if (nonFinite) throw ValidationError("stuffIsosurface: the implicit function returned a non-finite value");
  return values;
}

template <StuffingLattice Lattice>
LatticeCrossings cutAndWarp(const ImplicitFunction& f, const Lattice& lattice, const std::vector<double>& values,
                            const MesherOptions& options) {
  LatticeCrossings crossings;
  crossings.signs.resize(values.size());
  std::transform(values.begin(), values.end(), crossings.signs.begin(), signOf);
  const std::vector<LatticeEdge> edges = lattice.signChangingEdges(crossings.signs);
  const std::vector<double> parameters = findCutParameters(f, lattice, edges, values, options);
  WarpFinder finder;
  for (std::size_t e = 0; e < edges.size(); ++e) {
    const auto [u, v] = edges[e];
    const Eigen::Vector3d xu = lattice.position(u), xv = lattice.position(v);
    const Eigen::Vector3d point = xu + parameters[e] * (xv - xu);
    crossings.cuts.emplace(edgeKey(u, v), point);
    // Long (axis-parallel) edges join vertices that differ in one coordinate.
    const bool isLong = (lattice.doubled(u) - lattice.doubled(v)).cwiseAbs().count() == 1;
    finder.addCut(u, v, parameters[e], point, (xv - xu).norm(), isLong ? options.alphaLong : options.alphaShort);
  }
  crossings.warped = finder.warp(crossings.signs);
  return crossings;
}

template std::vector<double> sampleLattice(const ImplicitFunction&, const BccLattice&, bool, const KnownValue&);
template std::vector<double> sampleLattice(const ImplicitFunction&, const GradedLattice&, bool, const KnownValue&);
template LatticeCrossings cutAndWarp(const ImplicitFunction&, const BccLattice&, const std::vector<double>&,
                                     const MesherOptions&);
template LatticeCrossings cutAndWarp(const ImplicitFunction&, const GradedLattice&, const std::vector<double>&,
                                     const MesherOptions&);

}  // namespace asyncfem::detail
