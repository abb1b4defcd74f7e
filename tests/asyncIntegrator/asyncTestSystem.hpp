// SPDX-License-Identifier: BSD-3-Clause
// Small linear test systems and a dense single-rate backward Euler reference.
#pragma once

#include <Eigen/Dense>
#include <asyncfem/asyncIntegrator/asyncBackwardEuler.hpp>
#include <asyncfem/hexElements/hexElementMatrices.hpp>
#include <asyncfem/integrator/registry.hpp>
#include <asyncfem/problem/problem.hpp>
#include <asyncfem/stiffnessMatrix/elementMatrices.hpp>
#include <cmath>
#include <memory>
#include <utility>
#include <vector>

#include "../common/testProblems.hpp"

namespace asyncfem::test {

/// The stiff-end bar of testProblems.hpp ([0,1] x [0,0.25] x [0,0.25], 8 x 2 x 2 cubes,
/// clamped at x = 0, stiff and light for x > 0.75) pulled on its x = 1 face ("xmax") by
/// f_y = -0.5 cos(40 t), f_z = 0.2 sin(25 t) N per vertex, from a random state (u0, v0).
struct TestSystem : TestBody {
  Eigen::VectorXd u0, v0;
};

inline TestSystem makeTestSystem(const ProblemSettings& settings, unsigned seed = 7) {
  TestSystem ts{TestBody(stiffEndBarProblem(settings)), {}, {}};
  const std::vector<int> pulled = ts.mesh.vertexSet("xmax");
  ts.system.externalForce = [pulled](double t, const Eigen::VectorXd&, const Eigen::VectorXd&, Eigen::VectorXd& f) {
    for (int v : pulled) {
      f[3 * v + 1] += -0.5 * std::cos(40.0 * t);
      f[3 * v + 2] += 0.2 * std::sin(25.0 * t);
    }
  };
  RandomState state = randomState(ts.system.freeDofs, seed, FixedDofDraws::drawnThenZeroed);
  ts.u0 = std::move(state.displacement);
  ts.v0 = std::move(state.velocity);
  return ts;
}

/// Linear FEM, consistent mass, Rayleigh damping D = alpha M + beta K (alpha in 1/s, beta in s).
inline TestSystem makeTestSystem(double alpha, double beta, unsigned seed = 7) {
  return makeTestSystem(testSettings(ForceModelType::linear, alpha, beta), seed);
}

/// The undamped test system as an integrator registry's context (hL = 0.01, 30 frames/s),
/// for the scene-settings parsers.
inline IntegratorContext barContext() {
  TestSystem ts = makeTestSystem(0, 0);
  IntegratorContext context;
  context.mesh = std::make_shared<const TetMesh>(ts.mesh);
  context.system = std::move(ts.system);
  context.timestep = 0.01;
  context.frameRate = 30.0;
  return context;
}

/// M, K(0) and D = alpha M + beta K of a system, dense, on its free DOFs.
struct DenseFreeMatrices {
  Eigen::MatrixXd M, K, D;
};

inline DenseFreeMatrices denseFreeMatrices(const DynamicSystem& system) {
  const std::vector<int>& free = system.freeDofs.freeToFull();
  Eigen::SparseMatrix<double> stiffness = system.forceModel->createStiffnessMatrix();
  system.forceModel->tangentStiffness(Eigen::VectorXd::Zero(system.numDofs()), stiffness);
  const Eigen::MatrixXd fullM = Eigen::MatrixXd(system.mass), fullK = Eigen::MatrixXd(stiffness);
  const auto nf = static_cast<Eigen::Index>(free.size());
  DenseFreeMatrices out{Eigen::MatrixXd(nf, nf), Eigen::MatrixXd(nf, nf), {}};
  for (Eigen::Index a = 0; a < nf; ++a)
    for (Eigen::Index b = 0; b < nf; ++b) {
      out.M(a, b) = fullM(free[static_cast<std::size_t>(a)], free[static_cast<std::size_t>(b)]);
      out.K(a, b) = fullK(free[static_cast<std::size_t>(a)], free[static_cast<std::size_t>(b)]);
    }
  out.D = system.rayleighMass * out.M + system.rayleighStiffness * out.K;
  return out;
}

/// The linear FEM stiffness of element e of either kind: 12 x 12 (tetrahedron) or 24 x 24
/// (hexahedron).
inline Eigen::MatrixXd elementLinearStiffness(const TetMesh& mesh, int e) {
  const Material& material = mesh.elementMaterial(e);
  if (mesh.isHexahedral()) {
    return hexLinearStiffness(mesh.hexahedronRestPositions(e), material.youngsModulus, material.poissonRatio);
  }
  return linearElementStiffness(mesh.elementRestPositions(e), material.youngsModulus, material.poissonRatio);
}

/// The consistent mass of element e of either kind.
inline Eigen::MatrixXd elementConsistentMass(const TetMesh& mesh, int e) {
  const double density = mesh.elementMaterial(e).density;
  if (mesh.isHexahedral()) return hexConsistentMass(mesh.hexahedronRestPositions(e), density);
  double volume = 0.0;
  shapeFunctionGradients(mesh.elementRestPositions(e), &volume);
  return consistentElementMass(std::abs(volume), density);
}

/// Dense single-rate backward Euler on the free DOFs (design note, paper Eq. 5), the
/// independent reference the asynchronous integrator is checked against.
class DenseBackwardEuler {
 public:
  explicit DenseBackwardEuler(const DynamicSystem& system) : system_(system) {
    DenseFreeMatrices dense = denseFreeMatrices(system);
    M_ = std::move(dense.M);
    K_ = std::move(dense.K);
    D_ = std::move(dense.D);
  }

  /// One step of size h from (u, v) at time t (full vectors), in place.
  void step(double h, double t, Eigen::VectorXd& u, Eigen::VectorXd& v) const {
    const FreeDofs& dofs = system_.freeDofs;
    Eigen::VectorXd fext = Eigen::VectorXd::Zero(u.size());
    if (system_.externalForce) system_.externalForce(t + h, u, v, fext);
    const Eigen::VectorXd uf = dofs.restrict(u), vf = dofs.restrict(v), ff = dofs.restrict(fext);
    const Eigen::MatrixXd A = M_ + h * D_ + h * h * K_;
    const Eigen::VectorXd b = h * (ff - K_ * uf - D_ * vf - h * K_ * vf);
    const Eigen::VectorXd dv = A.partialPivLu().solve(b);
    const Eigen::VectorXd vNew = vf + dv;
    const Eigen::VectorXd uNew = uf + h * vNew;
    u = dofs.expand(uNew);
    v = dofs.expand(vNew);
  }

 private:
  const DynamicSystem& system_;
  Eigen::MatrixXd M_, K_, D_;
};

/// ||a - b|| / max(||a||, ||b||) in the infinity norm (purely relative: states here are ~1e-3).
inline double relativeDifference(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  const double scale = std::max({1e-300, a.lpNorm<Eigen::Infinity>(), b.lpNorm<Eigen::Infinity>()});
  return (a - b).lpNorm<Eigen::Infinity>() / scale;
}

/// Default options with the given coupling.
inline AsyncOptions withCoupling(AsyncCoupling coupling) {
  AsyncOptions options;
  options.coupling = coupling;
  return options;
}

/// The scene-file name of a coupling, for test messages.
inline const char* couplingName(AsyncCoupling coupling) {
  return coupling == AsyncCoupling::stable ? "stable" : "paper";
}

/// Vertices of the mesh with rest x >= xMin.
inline std::vector<int> verticesBeyond(const TetMesh& mesh, double xMin) {
  std::vector<int> out;
  for (int v = 0; v < mesh.numVertices(); ++v)
    if (mesh.restPosition(v).x() >= xMin - 1e-12) out.push_back(v);
  return out;
}

/// Vertices with rest x within 1e-9 of one of the given planes.
inline std::vector<int> verticesOnPlanes(const TetMesh& mesh, std::initializer_list<double> planes) {
  std::vector<int> out;
  for (int v = 0; v < mesh.numVertices(); ++v)
    for (double x : planes)
      if (std::abs(mesh.restPosition(v).x() - x) < 1e-9) out.push_back(v);
  return out;
}

}  // namespace asyncfem::test
