// SPDX-License-Identifier: BSD-3-Clause
// Schroeder2011 at m > 1 against its definition: the equations (S1)-(S6) of
// docs/asynchronous-integrator.md ("Schroeder et al. 2011") assembled densely here, one
// substep at a time, from the mesh's element matrices, and solved by dense LU. Nothing of
// the integrator's own code is used (no blocks, no stepped weights, no projection class):
// a wrong weight, a missing term or a wrong set in the library makes the two trajectories
// part.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <asyncfem/asyncIntegrator/schroeder2011.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/problem/problem.hpp>
#include <asyncfem/stiffnessMatrix/elementMatrices.hpp>
#include <cmath>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "asyncTestSystem.hpp"

namespace asyncfem {
namespace {

// The stiff-end bar of testProblems.hpp with 8 x 1 x 1 cubes (36 vertices, 48 tets),
// clamped at x = 0, soft with a stiff light end x > 0.75: the outer layer S is every
// vertex with x >= 0.75 (12 vertices), the interior L the rest. Pulled at its free end (on
// S) and at one vertex of the middle (on L), both varying in time so that the substep
// times and the step's end time are both seen; a random initial state.
struct Bar : test::TestSystem {
  std::vector<int> outer;
};

Bar makeBar(double alpha, double beta) {
  const ProblemSettings settings = test::testSettings(ForceModelType::linear, alpha, beta);
  Bar bar{{test::TestBody(test::stiffEndBarProblem(settings, Eigen::Vector3i(8, 1, 1))), {}, {}}, {}};
  bar.outer = test::verticesBeyond(bar.mesh, 0.75);
  const std::vector<int> pulled = bar.mesh.vertexSet("xmax");
  int middle = -1;
  for (int v = 0; v < bar.mesh.numVertices() && middle < 0; ++v)
    if (std::abs(bar.mesh.restPosition(v).x() - 0.5) < 1e-12) middle = v;
  bar.system.externalForce = [pulled, middle](double t, const Eigen::VectorXd&, const Eigen::VectorXd&,
                                              Eigen::VectorXd& f) {
    for (const int v : pulled) {
      f[3 * v + 1] -= 0.5 * std::cos(40.0 * t);
      f[3 * v + 2] += 0.2 * std::sin(25.0 * t);
    }
    f[3 * middle] += 0.3 * std::sin(30.0 * t);
  };
  test::RandomState state = test::randomState(bar.system.freeDofs, 5, test::FixedDofDraws::skipped);
  bar.u0 = std::move(state.displacement);
  bar.v0 = std::move(state.velocity);
  return bar;
}

// Where the definition may be changed on purpose, to show that the comparison sees it.
enum class Mutation {
  none,
  outerLayerOverLargeStep,  // L's rows take the outer layer's elements over hL, not hS
  interiorOneSubstepAhead,  // (S2) with u^L_0 + r hS v^L_0 at substep r instead of (r - 1)
};

/// One large step of Schroeder2011 written from (S1)-(S6) on the free DOFs, with dense
/// matrices: M the row sums of the consistent mass (S1); K_out the stiffness of the
/// elements touching S (the outer layer's forces), K_in that of the others (the interior's),
/// both summed here from the mesh's linear FEM element matrices; D = alpha M + beta K.
/// Written per element group, the equations read
///
///   substep r = 1..m-1, S rows (S3), L at u^L_0 + (r - 1) hS v^L_0 and v^L_0 (S2):
///     M (v_r - v_{r-1}) = hS [ f_ext(t_0 + r hS) - f_0 - K_out (u_{r-1} - u_0) - alpha M w_r - beta K_out w_r ],
///     w_r = (v^S_r, v^L_0),  u^S_r = u^S_{r-1} + hS v^S_r,
///   the outer layer's impulse on L (S3):  J = - sum_r hS [ K_out (u_{r-1} - u_0 + beta w_r) ]^L,
///   filtered (S5):  J~ = (1 - rho) J + rho W Phi (Phi^T W Phi)^-1 Phi^T J  over L's free DOFs,
///   last substep and L's whole step together (S6), u^S_m = u^S_{m-1} + hS v^S_m, u^L_m = u^L_0 + hL v^L_m:
///     S rows:  M (v_m - v_{m-1}) = hS [ f_ext(t_1) - f_0 - K_out (u_m - u_0) - alpha M v_m - beta K_out v_m ]
///     L rows:  M (v_m - v_0) = hL [ f_ext(t_1) - f_0 - alpha M v_m - K_in (u_m - u_0 + beta v_m) ]
///                              - hS K_out (u_m - u_0 + beta v_m) + J~.
///
/// This is the documented block form term by term: every S row of K is K_out's (each such
/// entry comes from an element touching S), K_out on L x S is K^{LS}, on L x L it is the
/// interface elements' K_if^{II}, and K_in on L x L is (K - K_if)^{LL}. Phi spans the
/// translations and the infinitesimal rotations about the origin, the same span as about
/// the interior's centroid (they differ by translations), so the same projection. Each
/// substep's equations are affine in its unknowns: their matrix is assembled column by
/// column from the residual and solved by LU.
class DefinitionStep {
 public:
  DefinitionStep(const Bar& bar, int ratio, double rigidity, Mutation mutation = Mutation::none)
      : system_(bar.system), ratio_(ratio), rigidity_(rigidity), mutation_(mutation) {
    const TetMesh& mesh = bar.mesh;
    const FreeDofs& dofs = system_.freeDofs;
    const std::vector<int>& free = dofs.freeToFull();
    const auto nf = static_cast<Eigen::Index>(free.size());
    std::vector<bool> inS(static_cast<std::size_t>(mesh.numVertices()), false);
    for (const int v : bar.outer) inS[static_cast<std::size_t>(v)] = true;
    isS_.resize(static_cast<std::size_t>(nf));
    for (Eigen::Index a = 0; a < nf; ++a) isS_[static_cast<std::size_t>(a)] = inS[free[a] / 3];
    // (S1): row sums of the full consistent mass, on the free rows.
    const Eigen::MatrixXd fullMass(system_.mass);
    mass_ = Eigen::MatrixXd::Zero(nf, nf);
    for (Eigen::Index a = 0; a < nf; ++a) mass_(a, a) = fullMass.row(free[a]).sum();
    outerStiffness_ = Eigen::MatrixXd::Zero(nf, nf);
    innerStiffness_ = Eigen::MatrixXd::Zero(nf, nf);
    const std::vector<int>& fullToFree = dofs.fullToFree();
    for (int e = 0; e < mesh.numElements(); ++e) {
      const Eigen::Vector4i vertices = mesh.element(e);
      bool touchesS = false;
      for (int p = 0; p < 4; ++p) touchesS = touchesS || inS[static_cast<std::size_t>(vertices[p])];
      const Material& material = mesh.elementMaterial(e);
      const ElementMatrix ke =
          linearElementStiffness(mesh.elementRestPositions(e), material.youngsModulus, material.poissonRatio);
      Eigen::MatrixXd& target = touchesS ? outerStiffness_ : innerStiffness_;
      for (int p = 0; p < 12; ++p)
        for (int q = 0; q < 12; ++q) {
          const int a = fullToFree[static_cast<std::size_t>(3 * vertices[p / 3] + p % 3)];
          const int b = fullToFree[static_cast<std::size_t>(3 * vertices[q / 3] + q % 3)];
          if (a >= 0 && b >= 0) target(a, b) += ke(p, q);
        }
    }
    // Rigid modes of L's free DOFs at the rest positions (the step adds u_0).
    restPositions_ = Eigen::VectorXd(nf);
    for (Eigen::Index a = 0; a < nf; ++a) restPositions_[a] = mesh.restPosition(free[a] / 3)[free[a] % 3];
  }

  /// The whole stiffness K_out + K_in on the free DOFs (for the check that the element
  /// groups add up to the model's K).
  Eigen::MatrixXd stiffness() const { return outerStiffness_ + innerStiffness_; }

  /// One large step hL from (u, v) at time t (full vectors), in place.
  void step(double hL, double t, Eigen::VectorXd& u, Eigen::VectorXd& v) const {
    const FreeDofs& dofs = system_.freeDofs;
    const double alpha = system_.rayleighMass, beta = system_.rayleighStiffness;
    const int m = ratio_;
    const double hS = hL / m;
    const Eigen::VectorXd u0 = dofs.restrict(u), v0 = dofs.restrict(v);
    const Eigen::VectorXd f0 = stiffness() * u0;  // f_int(u_0) of the linear model
    const Eigen::Index nf = u0.size();
    const std::vector<Eigen::Index> sDofs = select(true), lDofs = select(false);

    // (S2), (S3): substeps r = 1..m-1 of S, L moving with v^L_0.
    Eigen::VectorXd uPrev = u0, vPrev = v0, impulse = Eigen::VectorXd::Zero(nf);
    for (int r = 1; r < m; ++r) {
      const int lag = mutation_ == Mutation::interiorOneSubstepAhead ? r : r - 1;
      for (const Eigen::Index a : lDofs) uPrev[a] = u0[a] + lag * hS * v0[a];
      const Eigen::VectorXd force = externalForce(t + r * hS) - f0 - outerStiffness_ * (uPrev - u0);
      const auto withVelocity = [&](const Eigen::VectorXd& vS) {
        Eigen::VectorXd w = v0;
        for (std::size_t k = 0; k < sDofs.size(); ++k) w[sDofs[k]] = vS[static_cast<Eigen::Index>(k)];
        return w;
      };
      const auto residual = [&](const Eigen::VectorXd& vS) {
        const Eigen::VectorXd w = withVelocity(vS);
        const Eigen::VectorXd all =
            mass_ * (w - vPrev) - hS * (force - alpha * (mass_ * w) - beta * (outerStiffness_ * w));
        return rows(all, sDofs);
      };
      const Eigen::VectorXd vS = solveAffine(residual, rows(vPrev, sDofs));
      const Eigen::VectorXd w = withVelocity(vS);
      impulse -= hS * (outerStiffness_ * (uPrev - u0 + beta * w));
      for (std::size_t k = 0; k < sDofs.size(); ++k) {
        const Eigen::Index a = sDofs[k];
        vPrev[a] = w[a];
        uPrev[a] += hS * w[a];
      }
    }
    for (const Eigen::Index a : sDofs) impulse[a] = 0.0;  // J acts on L's rows only

    // (S5): the force distributing projection over L's free DOFs at the frame-start positions.
    const auto nl = static_cast<Eigen::Index>(lDofs.size());
    Eigen::MatrixXd modes = Eigen::MatrixXd::Zero(nl, 6);
    Eigen::VectorXd weights(nl), local(nl);
    for (Eigen::Index k = 0; k < nl; ++k) {
      const Eigen::Index a = lDofs[static_cast<std::size_t>(k)];
      const int component = static_cast<int>(dofs.freeToFull()[static_cast<std::size_t>(a)] % 3);
      const Eigen::Index vertexStart = a - component;  // free DOFs of a vertex are consecutive here
      const Eigen::Vector3d x = restPositions_.segment<3>(vertexStart) + u0.segment<3>(vertexStart);
      modes(k, component) = 1.0;
      for (int axis = 0; axis < 3; ++axis) modes(k, 3 + axis) = Eigen::Vector3d::Unit(axis).cross(x)[component];
      weights[k] = mass_(a, a);
      local[k] = impulse[a];
    }
    const Eigen::MatrixXd weighted = weights.asDiagonal() * modes;
    const Eigen::VectorXd projected =
        weighted * (modes.transpose() * weighted).partialPivLu().solve(modes.transpose() * local);
    Eigen::VectorXd filtered = Eigen::VectorXd::Zero(nf);
    for (Eigen::Index k = 0; k < nl; ++k)
      filtered[lDofs[static_cast<std::size_t>(k)]] = (1.0 - rigidity_) * local[k] + rigidity_ * projected[k];

    // (S6): the last substep of S with L's whole step; the unknowns are v_m on every free DOF.
    const double outerStepOnL = mutation_ == Mutation::outerLayerOverLargeStep ? hL : hS;
    const Eigen::VectorXd fext = externalForce(t + hL);
    Eigen::VectorXd uBase = u0;  // u_m = uBase + h_row v_m
    for (const Eigen::Index a : sDofs) uBase[a] = uPrev[a];
    const auto endState = [&](const Eigen::VectorXd& vm) {
      Eigen::VectorXd um = uBase;
      for (const Eigen::Index a : sDofs) um[a] += hS * vm[a];
      for (const Eigen::Index a : lDofs) um[a] += hL * vm[a];
      return um;
    };
    const auto residual = [&](const Eigen::VectorXd& vm) {
      const Eigen::VectorXd um = endState(vm);
      const Eigen::VectorXd sRows = mass_ * (vm - vPrev) - hS * (fext - f0 - outerStiffness_ * (um - u0) -
                                                                 alpha * (mass_ * vm) - beta * (outerStiffness_ * vm));
      const Eigen::VectorXd lRows =
          mass_ * (vm - v0) - (hL * (fext - f0 - alpha * (mass_ * vm) - innerStiffness_ * (um - u0 + beta * vm)) -
                               outerStepOnL * (outerStiffness_ * (um - u0 + beta * vm)) + filtered);
      Eigen::VectorXd out(nf);
      for (Eigen::Index a = 0; a < nf; ++a) out[a] = isS_[static_cast<std::size_t>(a)] ? sRows[a] : lRows[a];
      return out;
    };
    Eigen::VectorXd start = v0;
    for (const Eigen::Index a : sDofs) start[a] = vPrev[a];
    const Eigen::VectorXd vm = solveAffine(residual, start);
    u = dofs.expand(endState(vm));
    v = dofs.expand(vm);
  }

 private:
  // The free DOFs of S (inS) or of L, ascending.
  std::vector<Eigen::Index> select(bool inS) const {
    std::vector<Eigen::Index> out;
    for (std::size_t a = 0; a < isS_.size(); ++a)
      if (isS_[a] == inS) out.push_back(static_cast<Eigen::Index>(a));
    return out;
  }

  static Eigen::VectorXd rows(const Eigen::VectorXd& all, const std::vector<Eigen::Index>& which) {
    Eigen::VectorXd out(static_cast<Eigen::Index>(which.size()));
    for (std::size_t k = 0; k < which.size(); ++k) out[static_cast<Eigen::Index>(k)] = all[which[k]];
    return out;
  }

  // f_ext(t) on the free DOFs (the load depends on time only).
  Eigen::VectorXd externalForce(double time) const {
    Eigen::VectorXd f = Eigen::VectorXd::Zero(system_.numDofs());
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(system_.numDofs());
    system_.externalForce(time, zero, zero, f);
    return system_.freeDofs.restrict(f);
  }

  // The root of an affine residual: its matrix column by column about a point near the
  // root (differences of unit steps are exact for an affine map but for round-off), then LU.
  static Eigen::VectorXd solveAffine(const std::function<Eigen::VectorXd(const Eigen::VectorXd&)>& residual,
                                     const Eigen::VectorXd& near) {
    const Eigen::VectorXd r0 = residual(near);
    Eigen::MatrixXd matrix(r0.size(), near.size());
    for (Eigen::Index j = 0; j < near.size(); ++j) {
      Eigen::VectorXd shifted = near;
      shifted[j] += 1.0;
      matrix.col(j) = residual(shifted) - r0;
    }
    return near - matrix.partialPivLu().solve(r0);
  }

  const DynamicSystem& system_;
  int ratio_;
  double rigidity_;
  Mutation mutation_;
  std::vector<bool> isS_;
  Eigen::MatrixXd mass_, outerStiffness_, innerStiffness_;
  Eigen::VectorXd restPositions_;
};

constexpr int kLargeSteps = 4;

/// The largest relative difference (infinity norm, u and v) between the library's
/// trajectory at `ratio` and rigidity and the definition's (which may differ), over
/// kLargeSteps large steps of hL.
double trajectoryDifference(const Bar& bar, double hL, int ratio, const Schroeder2011Options& options,
                            const DefinitionStep& definition) {
  Schroeder2011 integrator(bar.system, hL, {{"outer", bar.outer, ratio}}, options);
  integrator.setState(bar.u0, bar.v0);
  Eigen::VectorXd u = bar.u0, v = bar.v0;
  double worst = 0.0;
  for (int s = 0; s < kLargeSteps; ++s) {
    definition.step(hL, s * hL, u, v);
    integrator.step();
    worst = std::max({worst, test::relativeDifference(integrator.displacement(), u),
                      test::relativeDifference(integrator.velocity(), v)});
  }
  return worst;
}

// The round-off of the two routes: the definition solves each substep by dense LU of
// matrices whose condition number is below 1e3 here (measured 6e2, the (S6) matrix with
// the stiff end's K over hS and the soft part's over hL), the library by sparse Cholesky
// and LU of the same equations summed in another order; over 4 large steps of up to 3
// solves each, kappa * 1e-16 * a dozen solves is ~1e-12 (observed up to 2e-12, in the
// forced runs whose states grow). 1e-10 leaves margin and is nine orders of magnitude
// below the differences a changed coefficient makes (ComparisonSeesAChangedCoefficient).
constexpr double kTolerance = 1e-10;

// The largest hL whose substeps at `ratio` are stable (S7), times `fraction`: the
// library's own limit only picks the step size; the comparison does not depend on it.
double largeStepFor(const Bar& bar, int ratio, double fraction) {
  Schroeder2011Options probe;
  probe.force = true;
  const Schroeder2011 integrator(bar.system, 1e-3, {{"outer", bar.outer, ratio}}, probe);
  return fraction * ratio * integrator.largestStableSubstep(0);
}

TEST(Schroeder2011Definition, ElementGroupsAddUpToTheModelsStiffness) {
  // K_out + K_in of the definition is the force model's K: every element is in one group.
  // 1e-12 relative: the same element matrices summed in another order.
  const Bar bar = makeBar(0.0, 0.0);
  const DefinitionStep definition(bar, 2, 1.0);
  const Eigen::MatrixXd model = test::denseFreeMatrices(bar.system).K;
  EXPECT_LE((definition.stiffness() - model).cwiseAbs().maxCoeff(), 1e-12 * model.cwiseAbs().maxCoeff());
  EXPECT_EQ(bar.outer.size(), 12U);
  EXPECT_EQ(bar.mesh.numVertices(), 36);
}

TEST(Schroeder2011Definition, LibraryFollowsTheDefinitionAtRatiosTwoAndThree) {
  // Undamped and Rayleigh-damped, at 0.9 of the stability limit (S7) with rigidity 1 (the
  // default), 0 (no filter) and 0.5, and with the option force at 1.5 times the limit (the
  // same equations with unstable substeps: the build is refused without it, and the
  // definition still follows). Undamped at m = 2 the one explicit substep starts at u_0,
  // so J = 0 and rho changes nothing; every other case here has J != 0.
  for (const auto& [alpha, beta] : {std::pair{0.0, 0.0}, std::pair{0.3, 2e-3}}) {
    const Bar bar = makeBar(alpha, beta);
    for (const int ratio : {2, 3}) {
      for (const auto& [rigidity, force] :
           {std::pair{1.0, false}, std::pair{0.0, false}, std::pair{0.5, false}, std::pair{1.0, true}}) {
        Schroeder2011Options options;
        options.rigidity = rigidity;
        options.force = force;
        const double hL = largeStepFor(bar, ratio, force ? 1.5 : 0.9);
        if (force) {
          EXPECT_THROW(Schroeder2011(bar.system, hL, {{"outer", bar.outer, ratio}}), TimestepError);
        }
        const double difference = trajectoryDifference(bar, hL, ratio, options, DefinitionStep(bar, ratio, rigidity));
        EXPECT_LE(difference, kTolerance) << "alpha " << alpha << ", beta " << beta << ", m " << ratio << ", rigidity "
                                          << rigidity << ", force " << force << ", hL " << hL;
      }
    }
  }
}

TEST(Schroeder2011Definition, ComparisonSeesAChangedCoefficient) {
  // The same comparison against a definition changed in one place must fail by orders of
  // magnitude: another ratio (hS and the number of explicit substeps), another filter
  // weight rho, L's rows taking the outer layer's elements over hL instead of hS, and the
  // interior's position during the substeps one substep ahead. Damped, at m = 3: every
  // term of (S3)-(S6) is non-zero.
  const Bar bar = makeBar(0.3, 2e-3);
  const double hL = largeStepFor(bar, 3, 0.9);
  const Schroeder2011Options options;
  const double same = trajectoryDifference(bar, hL, 3, options, DefinitionStep(bar, 3, 1.0));
  const double otherRatio = trajectoryDifference(bar, hL, 3, options, DefinitionStep(bar, 2, 1.0));
  const double otherRigidity = trajectoryDifference(bar, hL, 3, options, DefinitionStep(bar, 3, 0.5));
  const double otherWeight =
      trajectoryDifference(bar, hL, 3, options, DefinitionStep(bar, 3, 1.0, Mutation::outerLayerOverLargeStep));
  const double otherLag =
      trajectoryDifference(bar, hL, 3, options, DefinitionStep(bar, 3, 1.0, Mutation::interiorOneSubstepAhead));
  std::cout << "definition vs library at m = 3: " << same << "; definition at m = 2: " << otherRatio
            << "; at rho = 0.5: " << otherRigidity << "; outer layer over hL on L's rows: " << otherWeight
            << "; interior one substep ahead: " << otherLag << "\n";
  EXPECT_LE(same, kTolerance);
  // 1e4 times the tolerance: each change is a change of the scheme, far above round-off.
  EXPECT_GT(otherRatio, 1e4 * kTolerance);
  EXPECT_GT(otherRigidity, 1e4 * kTolerance);
  EXPECT_GT(otherWeight, 1e4 * kTolerance);
  EXPECT_GT(otherLag, 1e4 * kTolerance);
}

}  // namespace
}  // namespace asyncfem
