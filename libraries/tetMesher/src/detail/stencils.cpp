// SPDX-License-Identifier: BSD-3-Clause
#include "detail/stencils.hpp"

#include <Eigen/Dense>
#include <asyncfem/core/error.hpp>
#include <utility>

#include "detail/bccLattice.hpp"
#include "detail/gradedLattice.hpp"

namespace asyncfem::detail {

template <StuffingLattice Lattice>
void StencilBuilder<Lattice>::fill(const std::array<long long, 4>& tet) {
  SignGroups g;
  for (long long v : tet) {
    const int s = crossings_.signs[static_cast<std::size_t>(v)];
    if (s < 0)
      g.neg[static_cast<std::size_t>(g.numNeg++)] = v;
    else if (s == 0)
      g.zero[static_cast<std::size_t>(g.numZero++)] = v;
    else
      g.pos[static_cast<std::size_t>(g.numPos++)] = v;
  }
  if (g.numNeg == 0) return;
  if (g.numPos == 0)
    emit(lat(tet[0]), lat(tet[1]), lat(tet[2]), lat(tet[3]));
  else if (g.numNeg == 1)
    fillOneInside(g);
  else if (g.numNeg == 2 && g.numZero == 1)
    fillPyramid(g);
  else if (g.numNeg == 2)
    fillTwoInsideTwoOutside(g);
  else
    fillThreeInside(g);
}

/// One inside vertex: a single tetrahedron from it, the surface vertices and the cut points
/// on its edges to the outside vertices.
template <StuffingLattice Lattice>
void StencilBuilder<Lattice>::fillOneInside(const SignGroups& g) {
  const long long n = g.neg[0];
  std::array<int, 4> t{lat(n), 0, 0, 0};
  std::size_t k = 1;
  for (int i = 0; i < g.numZero; ++i) t[k++] = lat(g.zero[static_cast<std::size_t>(i)]);
  for (int i = 0; i < g.numPos; ++i) t[k++] = cut(n, g.pos[static_cast<std::size_t>(i)]);
  emit(t[0], t[1], t[2], t[3]);
}

/// Two inside, one on the surface, one outside: a pyramid with its apex at the surface
/// vertex and its base quadrilateral in the face (p, n0, n1).
template <StuffingLattice Lattice>
void StencilBuilder<Lattice>::fillPyramid(const SignGroups& g) {
  const long long n0 = g.neg[0], n1 = g.neg[1], p = g.pos[0];
  const int apex = lat(g.zero[0]);
  const int A = lat(n0), B = lat(n1), cA = cut(p, n0), cB = cut(p, n1);
  if (diagonalAtFirst(n0, n1, p)) {
    emit(apex, A, B, cB);
    emit(apex, A, cB, cA);
  } else {
    emit(apex, A, B, cA);
    emit(apex, B, cB, cA);
  }
}

/// Two inside, two outside: a prism around the inside edge (n0, n1) whose two lattice
/// quadrilaterals follow the face rule; the third (inside the lattice tetrahedron) is split
/// so that the prism falls into three tetrahedra.
template <StuffingLattice Lattice>
void StencilBuilder<Lattice>::fillTwoInsideTwoOutside(const SignGroups& g) {
  const long long n0 = g.neg[0], n1 = g.neg[1], p0 = g.pos[0], p1 = g.pos[1];
  const std::array<int, 3> a{lat(n0), cut(p0, n0), cut(p1, n0)};
  const std::array<int, 3> b{lat(n1), cut(p0, n1), cut(p1, n1)};
  // Quad 0 is (a0, a1, b1, b0) in face (p0, n0, n1): Forward is a0 - b1 = n0 - c(p0, n1).
  // Quad 2 is (a2, a0, b0, b2) in face (p1, n0, n1): Forward is a2 - b0 = c(p1, n0) - n1.
  const Diagonal quad0 = diagonalAtFirst(n0, n1, p0) ? Diagonal::Forward : Diagonal::Backward;
  const Diagonal quad2 = diagonalAtFirst(n0, n1, p1) ? Diagonal::Backward : Diagonal::Forward;
  emitPrism(a, b, {quad0, Diagonal::Free, quad2});
}

/// Three inside, one outside: the corner at p is cut off, leaving a prism between the inside
/// face and the three cut points; each quadrilateral lies in a lattice face.
template <StuffingLattice Lattice>
void StencilBuilder<Lattice>::fillThreeInside(const SignGroups& g) {
  const long long p = g.pos[0];
  const std::array<long long, 3> o{g.neg[0], g.neg[1], g.neg[2]};
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

template <StuffingLattice Lattice>
Eigen::Vector3d StencilBuilder<Lattice>::position(long long v) const {
  const auto it = crossings_.warped.find(v);
  return it != crossings_.warped.end() ? it->second : lattice_.position(v);
}

/// Output index of lattice vertex v (created on first use).
template <StuffingLattice Lattice>
int StencilBuilder<Lattice>::lat(long long v) {
  const auto [it, inserted] = latticeOutput_.try_emplace(v, static_cast<int>(out_.positions.size()));
  if (inserted) {
    out_.positions.push_back(position(v));
    out_.sources.push_back(v);
  }
  return it->second;
}

/// Output index of the cut point on lattice edge (u, v).
template <StuffingLattice Lattice>
int StencilBuilder<Lattice>::cut(long long u, long long v) {
  const std::uint64_t key = edgeKey(u, v);
  const auto [it, inserted] = cutOutput_.try_emplace(key, static_cast<int>(out_.positions.size()));
  if (inserted) {
    const auto found = crossings_.cuts.find(key);
    if (found == crossings_.cuts.end()) throw Error("stuffIsosurface: internal error: missing cut point");
    out_.positions.push_back(found->second);
    out_.sources.push_back(-1);
    ++out_.cutPointsUsed;
  }
  return it->second;
}

/// The quadrilateral (A, B, c(P,B), c(P,A)) that a lattice face (P, A, B) with A, B inside
/// and P outside leaves is split either by the diagonal A - c(P,B) (returns true) or by
/// B - c(P,A). Every lattice face has one long edge (axis-parallel: black-black or red-red)
/// and two short ones. If the long edge runs from P, its cut point takes the diagonal; if it
/// is A - B, the paper's parity rule decides: with c the cut point on B - P, count the
/// coordinates in which A exceeds c; A - c is the diagonal when that count is even on a red
/// long edge or odd on a black one. The rule depends only on the face (swapping A and B
/// flips the count's parity), so the two lattice tetrahedra sharing the face agree, and it
/// is what the angle bound of the paper assumes.
template <StuffingLattice Lattice>
bool StencilBuilder<Lattice>::diagonalAtFirst(long long A, long long B, long long P) const {
  const Eigen::Vector3i a = lattice_.doubled(A), b = lattice_.doubled(B), p = lattice_.doubled(P);
  const bool redA = lattice_.isRed(A), redB = lattice_.isRed(B), redP = lattice_.isRed(P);
  if (redP == redA) return false;  // long edge P - A: c(P,A) takes the diagonal to B
  if (redP == redB) return true;   // long edge P - B: c(P,B) takes the diagonal to A
  // Long edge A - B. c lies strictly inside B - P, so each coordinate of A - c has the sign
  // of 2A - B - P (doubled lattice coordinates, never zero).
  const Eigen::Vector3i d = 2 * a - b - p;
  const int exceeds = (d.x() > 0) + (d.y() > 0) + (d.z() > 0);
  return (exceeds + (redA ? 0 : 1)) % 2 == 0;
}

template <StuffingLattice Lattice>
void StencilBuilder<Lattice>::emit(int a, int b, int c, int d) {
  Eigen::Vector4i t(a, b, c, d);
  const std::vector<Eigen::Vector3d>& x = out_.positions;
  const Eigen::Vector3d x0 = x[static_cast<std::size_t>(a)];
  Eigen::Matrix3d edges;
  edges << x[static_cast<std::size_t>(b)] - x0, x[static_cast<std::size_t>(c)] - x0,
      x[static_cast<std::size_t>(d)] - x0;
  if (edges.determinant() < 0.0) std::swap(t[2], t[3]);
  out_.elements.push_back(t);
}

/// Pyramid with apex x over the quad (q0, q1, q2, q3), split along q0-q2 or q1-q3.
template <StuffingLattice Lattice>
void StencilBuilder<Lattice>::emitPyramid(int x, const std::array<int, 4>& q, bool diagonal02) {
  if (diagonal02) {
    emit(x, q[0], q[1], q[2]);
    emit(x, q[0], q[2], q[3]);
  } else {
    emit(x, q[1], q[2], q[3]);
    emit(x, q[1], q[3], q[0]);
  }
}

/// The diagonal of free quad i: the shorter, unless that would make the three diagonals
/// cyclic, which no three-tetrahedron split can honour.
template <StuffingLattice Lattice>
auto StencilBuilder<Lattice>::freeDiagonal(const std::array<int, 3>& a, const std::array<int, 3>& b,
                                           const std::array<Diagonal, 3>& diagonals, int i) const -> Diagonal {
  const Diagonal other1 = diagonals[static_cast<std::size_t>((i + 1) % 3)];
  const Diagonal other2 = diagonals[static_cast<std::size_t>((i + 2) % 3)];
  const std::size_t i0 = static_cast<std::size_t>(i), i1 = static_cast<std::size_t>((i + 1) % 3);
  const std::vector<Eigen::Vector3d>& x = out_.positions;
  const double forward = (x[static_cast<std::size_t>(a[i0])] - x[static_cast<std::size_t>(b[i1])]).norm();
  const double backward = (x[static_cast<std::size_t>(a[i1])] - x[static_cast<std::size_t>(b[i0])]).norm();
  Diagonal choice = forward <= backward ? Diagonal::Forward : Diagonal::Backward;
  if (other1 == other2 && other1 == choice)
    choice = choice == Diagonal::Forward ? Diagonal::Backward : Diagonal::Forward;
  return choice;
}

/// Prism with triangles a and b and lateral edges a_i - b_i. Quad i is
/// (a_i, a_{i+1}, b_{i+1}, b_i); Forward means its diagonal a_i - b_{i+1}, Backward
/// a_{i+1} - b_i, Free lets freeDiagonal choose.
template <StuffingLattice Lattice>
void StencilBuilder<Lattice>::emitPrism(const std::array<int, 3>& a, const std::array<int, 3>& b,
                                        std::array<Diagonal, 3> diagonals) {
  for (int i = 0; i < 3; ++i)
    if (diagonals[static_cast<std::size_t>(i)] == Diagonal::Free)
      diagonals[static_cast<std::size_t>(i)] = freeDiagonal(a, b, diagonals, i);
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

template class StencilBuilder<BccLattice>;
template class StencilBuilder<GradedLattice>;

}  // namespace asyncfem::detail
