// SPDX-License-Identifier: BSD-3-Clause
#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <asyncfem/core/error.hpp>
#include <asyncfem/tetMesher/isosurfaceStuffing.hpp>
#include <asyncfem/tetMesher/meshChecks.hpp>
#include <asyncfem/volumetricMesh/queries.hpp>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <unordered_map>
#include <vector>

#include "gradedLattice.hpp"

namespace asyncfem {

namespace {

/// The body-centred cubic lattice: black vertices at the corners of n cubes of size h,
/// red vertices at their centres. Ids: black first (x fastest), then red.
struct BccLattice {
  Eigen::Vector3d origin;
  double spacing = 0.0;
  Eigen::Array3i cells;  // cubes per axis

  long long numBlack() const { return static_cast<long long>(cells.x() + 1) * (cells.y() + 1) * (cells.z() + 1); }
  long long numRed() const { return static_cast<long long>(cells.x()) * cells.y() * cells.z(); }
  long long numVertices() const { return numBlack() + numRed(); }
  bool isRed(long long id) const { return id >= numBlack(); }

  long long black(int i, int j, int k) const {
    return i + static_cast<long long>(cells.x() + 1) * (j + static_cast<long long>(cells.y() + 1) * k);
  }
  long long red(int i, int j, int k) const {
    return numBlack() + i + static_cast<long long>(cells.x()) * (j + static_cast<long long>(cells.y()) * k);
  }
  /// Twice the lattice coordinates: black (2i, 2j, 2k), red (2i+1, 2j+1, 2k+1).
  Eigen::Vector3i doubled(long long id) const {
    if (!isRed(id)) {
      const long long nx = cells.x() + 1, ny = cells.y() + 1;
      return 2 * Eigen::Vector3i(static_cast<int>(id % nx), static_cast<int>((id / nx) % ny),
                                 static_cast<int>(id / (nx * ny)));
    }
    const long long r = id - numBlack();
    const long long nx = cells.x(), ny = cells.y();
    return 2 * Eigen::Vector3i(static_cast<int>(r % nx), static_cast<int>((r / nx) % ny),
                               static_cast<int>(r / (nx * ny))) +
           Eigen::Vector3i::Ones();
  }
  Eigen::Vector3d position(long long id) const {
    if (!isRed(id)) {
      const long long nx = cells.x() + 1, ny = cells.y() + 1;
      return origin + spacing * Eigen::Vector3d(static_cast<double>(id % nx), static_cast<double>((id / nx) % ny),
                                                static_cast<double>(id / (nx * ny)));
    }
    const long long r = id - numBlack();
    const long long nx = cells.x(), ny = cells.y();
    return origin + spacing * Eigen::Vector3d(static_cast<double>(r % nx) + 0.5,
                                              static_cast<double>((r / nx) % ny) + 0.5,
                                              static_cast<double>(r / (nx * ny)) + 0.5);
  }
};

int signOf(double value) { return value < 0.0 ? -1 : (value > 0.0 ? 1 : 0); }

std::uint64_t edgeKey(long long a, long long b) {
  const auto lo = static_cast<std::uint64_t>(std::min(a, b));
  const auto hi = static_cast<std::uint64_t>(std::max(a, b));
  return (hi << 32) ^ lo ^ (hi >> 32);  // ids fit in 32 bits (checked), so this is injective
}

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

/// Boundary edges (vertex pairs) shared by more than two boundary triangles.
std::vector<std::pair<int, int>> nonManifoldBoundaryEdges(const TetMesh& mesh) {
  std::map<std::pair<int, int>, int> count;
  for (const auto& t : boundaryTriangles(mesh))
    for (int i = 0; i < 3; ++i) {
      const int a = t[static_cast<std::size_t>(i)], b = t[static_cast<std::size_t>((i + 1) % 3)];
      ++count[{std::min(a, b), std::max(a, b)}];
    }
  std::vector<std::pair<int, int>> edges;
  for (const auto& [edge, uses] : count)
    if (uses > 2) edges.push_back(edge);
  return edges;
}

/// Builds the output mesh tetrahedron by tetrahedron. Lattice gives each lattice vertex's
/// position, doubled integer coordinates and colour (BccLattice, detail::GradedTetrahedra).
template <class Lattice>
class StencilBuilder {
 public:
  StencilBuilder(const Lattice& lattice, const std::vector<int>& signs,
                 const std::unordered_map<long long, Eigen::Vector3d>& warped,
                 const std::unordered_map<std::uint64_t, Eigen::Vector3d>& cuts)
      : lattice_(lattice), signs_(signs), warped_(warped), cuts_(cuts) {}

  /// Fills the part of lattice tetrahedron `tet` where f <= 0 with the stencil of its sign
  /// pattern (Labelle & Shewchuk 2007, Figure 4; - inside, 0 on the surface, + outside).
  void fill(const std::array<long long, 4>& tet) {
    std::array<long long, 4> neg{}, zero{}, pos{};
    int numNeg = 0, numZero = 0, numPos = 0;
    for (long long v : tet) {
      const int s = signs_[static_cast<std::size_t>(v)];
      if (s < 0)
        neg[static_cast<std::size_t>(numNeg++)] = v;
      else if (s == 0)
        zero[static_cast<std::size_t>(numZero++)] = v;
      else
        pos[static_cast<std::size_t>(numPos++)] = v;
    }
    // No inside vertex: nothing to fill. This includes tetrahedra whose four vertices all lie
    // on the surface, which the stencils discard.
    if (numNeg == 0) return;
    if (numPos == 0) {
      emit(lat(tet[0]), lat(tet[1]), lat(tet[2]), lat(tet[3]));
      return;
    }
    if (numNeg == 1) {
      // One inside vertex: a single tetrahedron from it, the surface vertices and the cut
      // points on its edges to the outside vertices.
      const long long n = neg[0];
      std::array<int, 4> t{lat(n), 0, 0, 0};
      int k = 1;
      for (int i = 0; i < numZero; ++i) t[static_cast<std::size_t>(k++)] = lat(zero[static_cast<std::size_t>(i)]);
      for (int i = 0; i < numPos; ++i) t[static_cast<std::size_t>(k++)] = cut(n, pos[static_cast<std::size_t>(i)]);
      emit(t[0], t[1], t[2], t[3]);
      return;
    }
    if (numNeg == 2 && numZero == 1) {
      // Pyramid: apex at the surface vertex, base quadrilateral in the face (p, n0, n1).
      const long long n0 = neg[0], n1 = neg[1], p = pos[0];
      const int apex = lat(zero[0]);
      const int A = lat(n0), B = lat(n1), cA = cut(p, n0), cB = cut(p, n1);
      if (diagonalAtFirst(n0, n1, p)) {
        emit(apex, A, B, cB);
        emit(apex, A, cB, cA);
      } else {
        emit(apex, A, B, cA);
        emit(apex, B, cB, cA);
      }
      return;
    }
    if (numNeg == 2) {
      // Two inside, two outside: a prism around the inside edge (n0, n1) whose two lattice
      // quadrilaterals follow the face rule; the third (inside the lattice tetrahedron) is
      // split so that the prism falls into three tetrahedra.
      const long long n0 = neg[0], n1 = neg[1], p0 = pos[0], p1 = pos[1];
      const std::array<int, 3> a{lat(n0), cut(p0, n0), cut(p1, n0)};
      const std::array<int, 3> b{lat(n1), cut(p0, n1), cut(p1, n1)};
      // Quad 0 is (a0, a1, b1, b0) in face (p0, n0, n1): Forward is a0 - b1 = n0 - c(p0, n1).
      // Quad 2 is (a2, a0, b0, b2) in face (p1, n0, n1): Forward is a2 - b0 = c(p1, n0) - n1.
      const Diagonal quad0 = diagonalAtFirst(n0, n1, p0) ? Diagonal::Forward : Diagonal::Backward;
      const Diagonal quad2 = diagonalAtFirst(n0, n1, p1) ? Diagonal::Backward : Diagonal::Forward;
      emitPrism(a, b, {quad0, Diagonal::Free, quad2});
      return;
    }
    // Three inside, one outside: the corner at p is cut off, leaving a prism between the
    // inside face and the three cut points; each quadrilateral lies in a lattice face.
    const long long p = pos[0];
    const std::array<long long, 3> o{neg[0], neg[1], neg[2]};
    std::array<int, 3> a{}, b{};
    std::array<Diagonal, 3> diagonals{};
    for (std::size_t i = 0; i < 3; ++i) {
      a[i] = lat(o[i]);
      b[i] = cut(p, o[i]);
    }
    // Quad i is (a_i, a_{i+1}, b_{i+1}, b_i): Forward is a_i - b_{i+1} = o_i - c(p, o_{i+1}).
    for (std::size_t i = 0; i < 3; ++i)
      diagonals[i] = diagonalAtFirst(o[i], o[(i + 1) % 3], p) ? Diagonal::Forward : Diagonal::Backward;
    emitPrism(a, b, diagonals);
  }

  std::vector<Eigen::Vector3d> positions;
  std::vector<Eigen::Vector4i> elements;
  std::vector<long long> sources;  // lattice vertex of each output vertex, -1 for cut points
  int cutPointsUsed = 0;

 private:
  enum class Diagonal { Forward, Backward, Free };

  Eigen::Vector3d position(long long v) const {
    const auto it = warped_.find(v);
    return it != warped_.end() ? it->second : lattice_.position(v);
  }

  /// Output index of lattice vertex v (created on first use).
  int lat(long long v) {
    const auto [it, inserted] = latticeOutput_.try_emplace(v, static_cast<int>(positions.size()));
    if (inserted) {
      positions.push_back(position(v));
      sources.push_back(v);
    }
    return it->second;
  }

  /// Output index of the cut point on lattice edge (u, v).
  int cut(long long u, long long v) {
    const std::uint64_t key = edgeKey(u, v);
    const auto [it, inserted] = cutOutput_.try_emplace(key, static_cast<int>(positions.size()));
    if (inserted) {
      const auto found = cuts_.find(key);
      if (found == cuts_.end()) throw Error("stuffIsosurface: internal error: missing cut point");
      positions.push_back(found->second);
      sources.push_back(-1);
      ++cutPointsUsed;
    }
    return it->second;
  }

  /// The quadrilateral (A, B, c(P,B), c(P,A)) that a lattice face (P, A, B) with A, B
  /// inside and P outside leaves is split either by the diagonal A - c(P,B) (returns true)
  /// or by B - c(P,A). Every lattice face has one long edge (axis-parallel: black-black or
  /// red-red) and two short ones. If the long edge runs from P, its cut point takes the
  /// diagonal; if it is A - B, the paper's parity rule decides: with c the cut point on
  /// B - P, count the coordinates in which A exceeds c; A - c is the diagonal when that
  /// count is even on a red long edge or odd on a black one. The rule depends only on the
  /// face (swapping A and B flips the count's parity), so the two lattice tetrahedra
  /// sharing the face agree, and it is what the angle bound of the paper assumes.
  bool diagonalAtFirst(long long A, long long B, long long P) const {
    const Eigen::Vector3i a = lattice_.doubled(A), b = lattice_.doubled(B), p = lattice_.doubled(P);
    const bool redA = lattice_.isRed(A), redB = lattice_.isRed(B), redP = lattice_.isRed(P);
    if (redP == redA) return false;  // long edge P - A: c(P,A) takes the diagonal to B
    if (redP == redB) return true;   // long edge P - B: c(P,B) takes the diagonal to A
    // Long edge A - B. c lies strictly inside B - P, so each coordinate of A - c has the
    // sign of 2A - B - P (doubled lattice coordinates, never zero).
    const Eigen::Vector3i d = 2 * a - b - p;
    const int exceeds = (d.x() > 0) + (d.y() > 0) + (d.z() > 0);
    return (exceeds + (redA ? 0 : 1)) % 2 == 0;
  }

  void emit(int a, int b, int c, int d) {
    Eigen::Vector4i t(a, b, c, d);
    const Eigen::Vector3d x0 = positions[static_cast<std::size_t>(a)];
    Eigen::Matrix3d edges;
    edges << positions[static_cast<std::size_t>(b)] - x0, positions[static_cast<std::size_t>(c)] - x0,
        positions[static_cast<std::size_t>(d)] - x0;
    if (edges.determinant() < 0.0) std::swap(t[2], t[3]);
    elements.push_back(t);
  }

  /// Pyramid with apex x over the quad (q0, q1, q2, q3), split along q0-q2 or q1-q3.
  void emitPyramid(int x, const std::array<int, 4>& q, bool diagonal02) {
    if (diagonal02) {
      emit(x, q[0], q[1], q[2]);
      emit(x, q[0], q[2], q[3]);
    } else {
      emit(x, q[1], q[2], q[3]);
      emit(x, q[1], q[3], q[0]);
    }
  }

  /// Prism with triangles a and b and lateral edges a_i - b_i. Quad i is
  /// (a_i, a_{i+1}, b_{i+1}, b_i); Forward means its diagonal a_i - b_{i+1}, Backward
  /// a_{i+1} - b_i, Free lets this function choose (the shorter, unless that would make
  /// the three diagonals cyclic, which no three-tetrahedron split can honour).
  void emitPrism(const std::array<int, 3>& a, const std::array<int, 3>& b, std::array<Diagonal, 3> diagonals) {
    for (int i = 0; i < 3; ++i) {
      if (diagonals[static_cast<std::size_t>(i)] != Diagonal::Free) continue;
      const Diagonal other1 = diagonals[static_cast<std::size_t>((i + 1) % 3)];
      const Diagonal other2 = diagonals[static_cast<std::size_t>((i + 2) % 3)];
      const std::size_t i0 = static_cast<std::size_t>(i), i1 = static_cast<std::size_t>((i + 1) % 3);
      const double forward =
          (positions[static_cast<std::size_t>(a[i0])] - positions[static_cast<std::size_t>(b[i1])]).norm();
      const double backward =
          (positions[static_cast<std::size_t>(a[i1])] - positions[static_cast<std::size_t>(b[i0])]).norm();
      Diagonal choice = forward <= backward ? Diagonal::Forward : Diagonal::Backward;
      if (other1 == other2 && other1 == choice)
        choice = choice == Diagonal::Forward ? Diagonal::Backward : Diagonal::Forward;
      diagonals[static_cast<std::size_t>(i)] = choice;
    }
    for (int i = 0; i < 3; ++i) {
      const std::size_t prev = static_cast<std::size_t>((i + 2) % 3), cur = static_cast<std::size_t>(i);
      const std::size_t next = static_cast<std::size_t>((i + 1) % 3), after = static_cast<std::size_t>((i + 2) % 3);
      // The quad opposite vertex a_i / b_i is quad i+1: (a_{i+1}, a_{i+2}, b_{i+2}, b_{i+1}).
      const std::array<int, 4> opposite{a[next], a[after], b[after], b[next]};
      const bool opposite02 = diagonals[next] == Diagonal::Forward;
      if (diagonals[prev] == Diagonal::Backward && diagonals[cur] == Diagonal::Forward) {
        // Both diagonals at a_i: cut off tetrahedron (a_i, b_0, b_1, b_2).
        emit(a[cur], b[0], b[1], b[2]);
        emitPyramid(a[cur], opposite, opposite02);
        return;
      }
      if (diagonals[prev] == Diagonal::Forward && diagonals[cur] == Diagonal::Backward) {
        emit(b[cur], a[0], a[1], a[2]);
        emitPyramid(b[cur], opposite, opposite02);
        return;
      }
    }
    throw Error("stuffIsosurface: internal error: cyclic prism diagonals");
  }

  const Lattice& lattice_;
  const std::vector<int>& signs_;
  const std::unordered_map<long long, Eigen::Vector3d>& warped_;
  const std::unordered_map<std::uint64_t, Eigen::Vector3d>& cuts_;
  std::unordered_map<long long, int> latticeOutput_;
  std::unordered_map<std::uint64_t, int> cutOutput_;
};

/// Step 3 of the method: for each lattice vertex, the closest cut point on one of its edges
/// that lies within alpha times the edge's length of it.
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

/// f at every lattice vertex (in parallel when asked), with known values reused; throws for
/// a non-finite value.
template <class Lattice>
std::vector<double> sampleLattice(const ImplicitFunction& f, const Lattice& lattice, long long numVertices,
                                  bool parallel, const std::function<bool(long long, double&)>& known = {}) {
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

/// Steps 4 to 6, shared by the uniform and the graded lattice: the stencils (fillAll(builder)
/// visits every lattice tetrahedron and returns how many), the optional pinch repair, the
/// angle guard, the checks and the report.
template <class Lattice, class FillAll>
TetMesh assembleStuffedMesh(const Lattice& lattice, const std::vector<double>& values, std::vector<int>& signs,
                            std::unordered_map<long long, Eigen::Vector3d>& warped,
                            const std::unordered_map<std::uint64_t, Eigen::Vector3d>& cuts, const FillAll& fillAll,
                            double spacing, const MesherOptions& options, StuffingReport* report) {
  // Where the surface is thinner than the lattice resolves, two warped vertices can pinch
  // two sheets of the boundary together along an edge. Such vertices go back to their
  // lattice positions (their cut points are known from step 2), which restores the
  // marching-tetrahedra structure there, and the stencils are rebuilt.
  int unwarped = 0;
  for (int attempt = 0;; ++attempt) {
    StencilBuilder<Lattice> builder(lattice, signs, warped, cuts);
    const long long latticeTets = fillAll(builder);
    if (builder.elements.empty()) {
      std::ostringstream message;
      message << "stuffIsosurface: no element: no lattice vertex lies inside the solid at spacing " << spacing;
      if (*std::min_element(values.begin(), values.end()) >= 0.0)
        message << " (f >= 0 at every one: the solid is thinner than the lattice everywhere, or empty, or f is not "
                   "negative inside); try a spacing below "
                << 0.5 * spacing;
      throw ValidationError(message.str());
    }
    Eigen::Matrix3Xd positions(3, static_cast<Eigen::Index>(builder.positions.size()));
    for (std::size_t v = 0; v < builder.positions.size(); ++v)
      positions.col(static_cast<Eigen::Index>(v)) = builder.positions[v];
    Eigen::Matrix4Xi elements(4, static_cast<Eigen::Index>(builder.elements.size()));
    for (std::size_t e = 0; e < builder.elements.size(); ++e)
      elements.col(static_cast<Eigen::Index>(e)) = builder.elements[e];
    TetMesh mesh(std::move(positions), std::move(elements), {options.material},
                 std::vector<int>(builder.elements.size(), 0));
    std::vector<long long> pinched;
    if (options.repairPinches && attempt < 32) {
      for (const auto& [a, b] : nonManifoldBoundaryEdges(mesh)) {
        for (int v : {a, b}) {
          const long long source = builder.sources[static_cast<std::size_t>(v)];
          if (source >= 0 && warped.count(source) > 0) pinched.push_back(source);
        }
      }
    }
    if (!pinched.empty()) {
      for (long long v : pinched) {
        if (warped.erase(v) > 0) {
          signs[static_cast<std::size_t>(v)] = signOf(values[static_cast<std::size_t>(v)]);
          ++unwarped;
        }
      }
      continue;
    }
    const MeshQuality quality = meshQuality(mesh);
    if (options.minDihedralDegrees > 0.0 && unwarped == 0 && quality.minDihedralDegrees < options.minDihedralDegrees) {
      // Not the input's fault: the stencils guarantee 10.78 degrees for any function.
      const std::vector<ElementQuality> qualities = elementQualities(mesh);
      int worst = 0;
      for (int e = 1; e < mesh.numElements(); ++e)
        if (qualities[static_cast<std::size_t>(e)].minDihedralAngle <
            qualities[static_cast<std::size_t>(worst)].minDihedralAngle)
          worst = e;
      const Eigen::Vector3d centre = mesh.elementRestPositions(worst).rowwise().mean();
      std::ostringstream message;
      message << "stuffIsosurface: internal error: element " << worst << " near (" << centre.x() << ", " << centre.y()
              << ", " << centre.z() << ") has a dihedral angle of " << quality.minDihedralDegrees
              << " degrees, below the guaranteed " << options.minDihedralDegrees << " (spacing " << spacing
              << ", alphaLong " << options.alphaLong << ", alphaShort " << options.alphaShort
              << "; the bound holds for the default alphas); the mesh was not returned";
      throw Error(message.str());
    }
    if (options.check) {
      validateTetMesh(mesh, "stuffIsosurface (spacing " + std::to_string(spacing) + ")");
    }
    if (report != nullptr) {
      report->latticeVertices = static_cast<long long>(values.size());
      report->latticeTetrahedra = latticeTets;
      report->cutPoints = builder.cutPointsUsed;
      report->warpedVertices = static_cast<int>(warped.size());
      report->unwarpedVertices = unwarped;
      report->elements = mesh.numElements();
      report->vertices = mesh.numVertices();
      report->minDihedralDegrees = quality.minDihedralDegrees;
      report->maxDihedralDegrees = quality.maxDihedralDegrees;
      report->pinchedBoundaryEdges = static_cast<int>(nonManifoldBoundaryEdges(mesh).size());
    }
    return mesh;
  }
}

void checkLatticeSize(long long numLattice, const MesherOptions& options) {
  const long long limit = std::min<long long>(options.maxLatticeVertices, std::numeric_limits<std::int32_t>::max());
  if (numLattice > limit) {
    throw ValidationError("stuffIsosurface: the lattice would have " + std::to_string(numLattice) +
                          " vertices (limit " + std::to_string(limit) + "); use a larger spacing");
  }
}

TetMesh stuffUniform(const ImplicitFunction& f, const Eigen::AlignedBox3d& bounds, double spacing,
                     const MesherOptions& options, StuffingReport* report) {
  BccLattice lattice;
  lattice.spacing = spacing;
  // Two cells of margin on each side, so the outermost lattice layers lie outside the solid.
  lattice.origin = bounds.min() - Eigen::Vector3d::Constant(2.0 * spacing);
  const Eigen::Array3d extent = (bounds.max() - bounds.min()).array() / spacing;
  for (int a = 0; a < 3; ++a) {
    const double cells = std::ceil(extent[a]) + 4.0;
    if (cells > 1e6) throw ValidationError("stuffIsosurface: spacing too small for the bounds");
    lattice.cells[a] = static_cast<int>(cells);
  }
  const long long numLattice = lattice.numVertices();
  checkLatticeSize(numLattice, options);

  // 1. Sample f at every lattice vertex.
  const std::vector<double> values = sampleLattice(f, lattice, numLattice, options.parallel);
  std::vector<int> signs(values.size());
  for (std::size_t v = 0; v < values.size(); ++v) signs[v] = signOf(values[v]);

  // 2. Cut points on sign-changing edges, and 3. the closest violating cut point per vertex.
  std::unordered_map<std::uint64_t, Eigen::Vector3d> cuts;
  WarpFinder finder;
  auto visitEdge = [&](long long u, long long v, double alpha) {
    const double fu = values[static_cast<std::size_t>(u)], fv = values[static_cast<std::size_t>(v)];
    if (!((fu < 0.0 && fv > 0.0) || (fu > 0.0 && fv < 0.0))) return;
    const Eigen::Vector3d xu = lattice.position(u), xv = lattice.position(v);
    const double t = findRoot(f, xu, xv, fu, fv, options.cutPointIterations);
    const Eigen::Vector3d point = xu + t * (xv - xu);
    cuts.emplace(edgeKey(u, v), point);
    finder.addCut(u, v, t, point, (xv - xu).norm(), alpha);
  };
  const Eigen::Array3i& n = lattice.cells;
  for (int k = 0; k <= n.z(); ++k)
    for (int j = 0; j <= n.y(); ++j)
      for (int i = 0; i <= n.x(); ++i) {
        const long long b = lattice.black(i, j, k);
        if (i < n.x()) visitEdge(b, lattice.black(i + 1, j, k), options.alphaLong);
        if (j < n.y()) visitEdge(b, lattice.black(i, j + 1, k), options.alphaLong);
        if (k < n.z()) visitEdge(b, lattice.black(i, j, k + 1), options.alphaLong);
      }
  for (int k = 0; k < n.z(); ++k)
    for (int j = 0; j < n.y(); ++j)
      for (int i = 0; i < n.x(); ++i) {
        const long long r = lattice.red(i, j, k);
        if (i + 1 < n.x()) visitEdge(r, lattice.red(i + 1, j, k), options.alphaLong);
        if (j + 1 < n.y()) visitEdge(r, lattice.red(i, j + 1, k), options.alphaLong);
        if (k + 1 < n.z()) visitEdge(r, lattice.red(i, j, k + 1), options.alphaLong);
        for (int corner = 0; corner < 8; ++corner) {
          visitEdge(r, lattice.black(i + (corner & 1), j + ((corner >> 1) & 1), k + ((corner >> 2) & 1)),
                    options.alphaShort);
        }
      }
  std::unordered_map<long long, Eigen::Vector3d> warped = finder.warp(signs);

  // 4. Stencils. Each BCC tetrahedron pairs the red edge between two face-adjacent cube
  // centres with one of the four black edges of the face they share.
  auto fillAll = [&](StencilBuilder<BccLattice>& builder) {
    long long latticeTets = 0;
    for (int k = 0; k < n.z(); ++k)
      for (int j = 0; j < n.y(); ++j)
        for (int i = 0; i < n.x(); ++i) {
          const Eigen::Array3i cell(i, j, k);
          for (int axis = 0; axis < 3; ++axis) {
            Eigen::Array3i next = cell;
            ++next[axis];
            if (next[axis] >= n[axis]) continue;
            const long long r0 = lattice.red(i, j, k), r1 = lattice.red(next.x(), next.y(), next.z());
            const int b = (axis + 1) % 3, d = (axis + 2) % 3;
            auto corner = [&](int s, int t) {
              Eigen::Array3i c = next;
              c[b] += s;
              c[d] += t;
              return lattice.black(c.x(), c.y(), c.z());
            };
            const std::array<std::array<long long, 2>, 4> blackEdges{{{corner(0, 0), corner(1, 0)},
                                                                      {corner(0, 1), corner(1, 1)},
                                                                      {corner(0, 0), corner(0, 1)},
                                                                      {corner(1, 0), corner(1, 1)}}};
            for (const auto& edge : blackEdges) {
              ++latticeTets;
              const std::array<long long, 4> tet{edge[0], edge[1], r0, r1};
              bool anyInside = false;
              for (long long v : tet) anyInside = anyInside || signs[static_cast<std::size_t>(v)] < 0;
              if (anyInside) builder.fill(tet);
            }
          }
        }
    return latticeTets;
  };
  return assembleStuffedMesh(lattice, values, signs, warped, cuts, fillAll, spacing, options, report);
}

TetMesh stuffGraded(const ImplicitFunction& f, const Eigen::AlignedBox3d& bounds, double spacing,
                    const MesherOptions& options, StuffingReport* report) {
  const int levels = options.gradingLevels;
  const double rootEdge = spacing * static_cast<double>(1 << levels);
  // At least two spacings of margin, in whole root cubes, so the outermost cubes lie outside.
  const double margin = rootEdge * std::ceil(2.0 * spacing / rootEdge);
  const Eigen::Vector3d origin = bounds.min() - Eigen::Vector3d::Constant(margin);
  Eigen::Array3i roots;
  for (int a = 0; a < 3; ++a) {
    const double cells = std::ceil((bounds.max()[a] - bounds.min()[a] + 2.0 * margin) / rootEdge);
    if (cells * static_cast<double>(1 << levels) > 1e6) {
      throw ValidationError("stuffIsosurface: spacing too small for the bounds");
    }
    roots[a] = static_cast<int>(cells);
  }
  // Every leaf cube brings about one black and one red lattice vertex: the cube count is
  // held to the lattice vertex limit.
  const long long maxCells = std::min<long long>(options.maxLatticeVertices, std::numeric_limits<std::int32_t>::max());
  detail::GradedGrid grid(origin, spacing, levels, roots, maxCells);
  // Every point within one spacing of the surface gets a finest cube (for a 1-Lipschitz f,
  // as distances are). That keeps every tetrahedron outside the finest lattice at least half
  // a spacing from the surface, beyond the reach of warping (alphaShort * sqrt(3)/2 < 0.36
  // spacings); what a non-distance f hides is caught below and refined.
  grid.refineNear(f, spacing, options.parallel);
  std::unordered_map<std::uint64_t, double> known = grid.values();
  int rounds = 0;
  for (;;) {
    const detail::GradedTetrahedra lattice = grid.tetrahedra();
    const long long numLattice = lattice.numVertices();
    checkLatticeSize(numLattice, options);
    const std::vector<double> values =
        sampleLattice(f, lattice, numLattice, options.parallel, [&](long long v, double& value) {
          const auto it = known.find(detail::GradedGrid::packKey(lattice.doubled(v)));
          if (it == known.end()) return false;
          value = it->second;
          return true;
        });
    for (long long v = 0; v < numLattice; ++v)
      known.emplace(detail::GradedGrid::packKey(lattice.doubled(v)), values[static_cast<std::size_t>(v)]);
    std::vector<int> signs(values.size());
    for (std::size_t v = 0; v < values.size(); ++v) signs[v] = signOf(values[v]);

    // 2. Cut points on the sign-changing edges of the finest tetrahedra (found in parallel).
    std::vector<std::pair<long long, long long>> edges;
    std::unordered_map<std::uint64_t, char> seen;
    for (std::size_t t = 0; t < lattice.tetrahedra.size(); ++t) {
      if (!lattice.plain[t]) continue;
      const auto& tet = lattice.tetrahedra[t];
      for (int i = 0; i < 4; ++i)
        for (int j = i + 1; j < 4; ++j) {
          const long long u = tet[static_cast<std::size_t>(i)], v = tet[static_cast<std::size_t>(j)];
          if (signs[static_cast<std::size_t>(u)] * signs[static_cast<std::size_t>(v)] >= 0) continue;
          if (seen.emplace(edgeKey(u, v), 1).second) edges.emplace_back(std::min(u, v), std::max(u, v));
        }
    }
    std::vector<double> parameters(edges.size());
    const long long numEdges = static_cast<long long>(edges.size());
#pragma omp parallel for schedule(dynamic, 64) if (options.parallel)
    for (long long e = 0; e < numEdges; ++e) {
      const auto [u, v] = edges[static_cast<std::size_t>(e)];
      parameters[static_cast<std::size_t>(e)] =
          findRoot(f, lattice.position(u), lattice.position(v), values[static_cast<std::size_t>(u)],
                   values[static_cast<std::size_t>(v)], options.cutPointIterations);
    }
    // 3. Warping; an edge is long (axis-parallel) when its ends differ in one coordinate.
    std::unordered_map<std::uint64_t, Eigen::Vector3d> cuts;
    WarpFinder finder;
    for (std::size_t e = 0; e < edges.size(); ++e) {
      const auto [u, v] = edges[e];
      const Eigen::Vector3d xu = lattice.position(u), xv = lattice.position(v);
      const Eigen::Vector3d point = xu + parameters[e] * (xv - xu);
      cuts.emplace(edgeKey(u, v), point);
      const bool isLong = (lattice.doubled(u) - lattice.doubled(v)).cwiseAbs().count() == 1;
      finder.addCut(u, v, parameters[e], point, (xv - xu).norm(), isLong ? options.alphaLong : options.alphaShort);
    }
    std::unordered_map<long long, Eigen::Vector3d> warped = finder.warp(signs);

    // The stencils' guarantee covers the finest tetrahedra only: every other one must lie
    // strictly on one side of the surface, untouched by warping. Where one does not (the
    // function is not a distance there), its cubes are refined and the lattice rebuilt.
    std::vector<int> toSplit;
    for (std::size_t t = 0; t < lattice.tetrahedra.size(); ++t) {
      if (lattice.plain[t]) continue;
      const auto& tet = lattice.tetrahedra[t];
      const int first = signs[static_cast<std::size_t>(tet[0])];
      bool uniform = first != 0;
      for (int i = 1; i < 4 && uniform; ++i)
        uniform = signs[static_cast<std::size_t>(tet[static_cast<std::size_t>(i)])] == first;
      if (uniform) continue;
      for (int owner : lattice.owners[t])
        if (owner >= 0) toSplit.push_back(owner);
    }
    if (!toSplit.empty()) {
      std::sort(toSplit.begin(), toSplit.end());
      toSplit.erase(std::unique(toSplit.begin(), toSplit.end()), toSplit.end());
      if (grid.splitLeaves(toSplit) == 0) {
        throw Error("stuffIsosurface: internal error: the surface meets a coarse cube that cannot be refined");
      }
      ++rounds;
      continue;
    }

    auto fillAll = [&](StencilBuilder<detail::GradedTetrahedra>& builder) {
      for (const auto& tet : lattice.tetrahedra) {
        bool anyInside = false;
        for (long long v : tet) anyInside = anyInside || signs[static_cast<std::size_t>(v)] < 0;
        if (anyInside) builder.fill(tet);
      }
      return static_cast<long long>(lattice.tetrahedra.size());
    };
    TetMesh mesh = assembleStuffedMesh(lattice, values, signs, warped, cuts, fillAll, spacing, options, report);
    if (report != nullptr) {
      report->gradingLevels = levels;
      report->latticeCells = grid.numLeaves();
      report->refinementRounds = rounds;
    }
    return mesh;
  }
}

}  // namespace

TetMesh stuffIsosurface(const ImplicitFunction& f, const Eigen::AlignedBox3d& bounds, double spacing,
                        const MesherOptions& options, StuffingReport* report) {
  if (!(spacing > 0.0) || !std::isfinite(spacing)) {
    throw ValidationError("stuffIsosurface: spacing must be a finite number > 0, got " + std::to_string(spacing));
  }
  if (bounds.isEmpty() || !bounds.min().allFinite() || !bounds.max().allFinite()) {
    throw ValidationError("stuffIsosurface: empty or non-finite bounds");
  }
  if (!f) throw ValidationError("stuffIsosurface: no implicit function");
  if (options.gradingLevels < 0 || options.gradingLevels > kMaxGradingLevels) {
    throw ValidationError("stuffIsosurface: gradingLevels must be between 0 and " + std::to_string(kMaxGradingLevels) +
                          ", got " + std::to_string(options.gradingLevels));
  }
  if (options.gradingLevels == 0) return stuffUniform(f, bounds, spacing, options, report);
  return stuffGraded(f, bounds, spacing, options, report);
}

}  // namespace asyncfem
