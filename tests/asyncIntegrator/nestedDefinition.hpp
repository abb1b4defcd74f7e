// SPDX-License-Identifier: BSD-3-Clause
// Eq. N3 of docs/asynchronous-integrator.md ("Nested and touching regions") evaluated
// directly on a hierarchy step's solution: the oracle of the nested-region tests.
#pragma once

#include <Eigen/Dense>
#include <algorithm>
#include <asyncfem/asyncIntegrator/asyncBackwardEuler.hpp>
#include <asyncfem/stiffnessMatrix/elementMatrices.hpp>
#include <cmath>
#include <utility>
#include <vector>

#include "asyncTestSystem.hpp"

namespace asyncfem::test {

/// The residual of Eq. N3 for every free DOF and step, written from the definition: each
/// vertex's motion rebuilt from its step velocities (Eq. N1), each element evaluated with
/// its own matrices on its fastest vertex's steps (Eq. N2), each impulse credited to the
/// step it falls in. The load on a step is f_ext at the step's end time and the start state
/// (u0, v0), or, with loadAtStepStates, at every DOF's state at that time (Eq. N13: implicit
/// contact). Returns max |residual| / max |term|.
inline double nestedDefinitionResidual(const TestSystem& ts, const AsyncBackwardEuler& nested,
                                       const Eigen::VectorXd& u0, const Eigen::VectorXd& v0, double hL, double t0,
                                       bool loadAtStepStates = false) {
  const TetMesh& mesh = ts.mesh;
  const DynamicSystem& system = ts.system;
  const RegionPartition& counts = nested.partition();
  const long long units = counts.units();
  const std::vector<int>& fullToFree = system.freeDofs.fullToFree();
  // Velocity and displacement of DOF i at time unit t (t = 0: the start state).
  const auto stepOf = [&](int i, long long t) {
    const long long s = units / counts.vertexCounts()[static_cast<std::size_t>(i / 3)];
    return std::pair<long long, long long>{(t + s - 1) / s, s};
  };
  const auto velocity = [&](int i, long long t) {
    const int d = fullToFree[static_cast<std::size_t>(i)];
    if (d < 0) return 0.0;
    const long long j = stepOf(i, t).first;
    return j == 0 ? v0[i] : nested.stepVelocities(d)[j - 1];
  };
  const auto displacement = [&](int i, long long t) {
    const int d = fullToFree[static_cast<std::size_t>(i)];
    if (d < 0 || t == 0) return d < 0 ? 0.0 : u0[i];
    const auto [j, s] = stepOf(i, t);
    const Eigen::VectorXd vs = nested.stepVelocities(d);
    const double h = hL / static_cast<double>(units / s);
    const double before = u0[i] + h * vs.head(j - 1).sum();
    return before + static_cast<double>(t - (j - 1) * s) * (hL / static_cast<double>(units)) * vs[j - 1];
  };
  // Impulse credited to each (DOF, step): element forces, then mass and load terms.
  std::vector<Eigen::VectorXd> impulse(static_cast<std::size_t>(mesh.numDofs()));
  for (int i = 0; i < mesh.numDofs(); ++i)
    impulse[static_cast<std::size_t>(i)] =
        Eigen::VectorXd::Zero(counts.vertexCounts()[static_cast<std::size_t>(i / 3)]);
  double scale = 0.0;
  for (int e = 0; e < mesh.numElements(); ++e) {
    const Eigen::MatrixXd ke = elementLinearStiffness(mesh, e);
    const Eigen::MatrixXd de = system.rayleighMass * elementConsistentMass(mesh, e) + system.rayleighStiffness * ke;
    const auto size = static_cast<int>(ke.rows());
    const int count = counts.elementCounts()[static_cast<std::size_t>(e)];
    for (int q = 1; q <= count; ++q) {
      const long long tq = q * (units / count);
      Eigen::VectorXd ue(size), ve(size);
      for (int a = 0; a < size; ++a) {
        const int i = 3 * mesh.elementVertex(e, a / 3) + a % 3;
        ue[a] = displacement(i, tq);
        ve[a] = velocity(i, tq);
      }
      const Eigen::VectorXd force = -(hL / count) * (ke * ue + de * ve);
      for (int a = 0; a < size; ++a) {
        const int i = 3 * mesh.elementVertex(e, a / 3) + a % 3;
        if (fullToFree[static_cast<std::size_t>(i)] < 0) continue;
        impulse[static_cast<std::size_t>(i)][stepOf(i, tq).first - 1] += force[a];
        scale = std::max(scale, std::abs(force[a]));
      }
    }
  }
  double worst = 0.0;
  const Eigen::MatrixXd mass(system.mass);
  for (int i = 0; i < mesh.numDofs(); ++i) {
    if (fullToFree[static_cast<std::size_t>(i)] < 0) continue;
    const int count = counts.vertexCounts()[static_cast<std::size_t>(i / 3)];
    const long long s = units / count;
    for (int j = 1; j <= count; ++j) {
      double momentum = 0.0;
      for (int p = 0; p < mesh.numDofs(); ++p)
        if (mass(i, p) != 0.0) momentum += mass(i, p) * (velocity(p, j * s) - velocity(p, (j - 1) * s));
      Eigen::VectorXd load = Eigen::VectorXd::Zero(mesh.numDofs());
      const double t = j == count ? t0 + hL : t0 + j * (hL / count);
      if (loadAtStepStates) {
        Eigen::VectorXd u(mesh.numDofs()), v(mesh.numDofs());
        for (int p = 0; p < mesh.numDofs(); ++p) {
          u[p] = displacement(p, j * s);
          v[p] = velocity(p, j * s);
        }
        system.externalForce(t, u, v, load);
      } else {
        system.externalForce(t, u0, v0, load);
      }
      const double residual = momentum - impulse[static_cast<std::size_t>(i)][j - 1] - (hL / count) * load[i];
      worst = std::max(worst, std::abs(residual));
      scale = std::max(scale, std::abs(momentum));
    }
  }
  return worst / scale;
}

}  // namespace asyncfem::test
