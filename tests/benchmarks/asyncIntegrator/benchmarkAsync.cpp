// SPDX-License-Identifier: BSD-3-Clause
// Benchmarks of the asynchronous integrator, printed as Markdown tables. Every time is a
// median of per-step wall times after warm-up steps, and every ratio compares two
// configurations measured in the same run.
//
//   benchmarkAsync --study growth   async vs single-rate at hL and hS as |S| grows, and the
//                                   solve floor (sparse solves alone) under each async step
//   benchmarkAsync --study ratio    structured vs naive as m grows
//   benchmarkAsync --study schur    exact vs symmetric H^{LL*}: time and trajectory difference
//   benchmarkAsync --study corotational
//                                   nonlinear async vs corotational single-rate at equal cost:
//                                   retained motion of S (the paper's Figure 8) and time split
//   benchmarkAsync --study steady --scenes A.json B.json ... [--dragon-spacing H]
//                                   per scene: set-up, steady-state async step against one
//                                   single-rate step at hL, and (--corotational) the async
//                                   frame against corotational single-rate at hS
//   benchmarkAsync --study setup --scenes A.json B.json ...
//                                   per scene: set-up and re-partition cost, exact against
//                                   AsyncOptions::KeptFactors::quickSetUp, in single-rate steps at hL
//   benchmarkAsync --study modes --scenes A.json B.json ... [--corotational]
//                                   per scene: set-up with Z by substitution and from the
//                                   regions' modes (AsyncOptions::zSolve) against single-rate's
//   benchmarkAsync --study steady --only async|single --scenes A.json --steps N
//                                   one configuration only, for callgrind: the steady steps
//                                   are the only ones collected (run under
//                                   valgrind --tool=callgrind --collect-atstart=no)
#include <CLI/CLI.hpp>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <asyncfem/asyncIntegrator/asyncBackwardEuler.hpp>
#include <asyncfem/asyncIntegrator/regionProposal.hpp>
#include <asyncfem/contact/penaltyContact.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/core/threading.hpp>
#include <asyncfem/corotationalLinearFEM/corotationalLinearFEM.hpp>
#include <asyncfem/forceModel/linearForceModel.hpp>
#include <asyncfem/integrator/factory.hpp>
#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/sceneIO/simulation.hpp>
#include <asyncfem/stiffnessMatrix/assembler.hpp>
#include <asyncfem/tetMesher/exampleModels.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <asyncfem/volumetricMesh/writers.hpp>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <numeric>
#include <string>
#include <thread>
#include <vector>

#if __has_include(<valgrind/callgrind.h>)
#include <valgrind/callgrind.h>

#include "../benchmarkMachine.hpp"
#define ASYNCFEM_COLLECT_ON() CALLGRIND_TOGGLE_COLLECT
#define ASYNCFEM_COLLECT_OFF() CALLGRIND_TOGGLE_COLLECT
#else
#define ASYNCFEM_COLLECT_ON()
#define ASYNCFEM_COLLECT_OFF()
#endif

namespace {

using asyncfem::bench::cpuModel;
using asyncfem::bench::loadAverage;

using namespace asyncfem;

struct Bench {
  TetMesh mesh;
  DynamicSystem system;
};

/// A cantilever bar along x, fixed at x = 0, body soft, last 10% stiff and light; a
/// constant downward pull on the free end.
Bench makeBench(int cellsAlong) {
  BeamSpec spec;
  spec.cellsAlongLength = cellsAlong;
  spec.tipFraction = 0.1;
  Bench b{makeBeamMesh(spec), {}};
  MatrixAssembler assembler(b.mesh);
  b.system.forceModel = std::make_shared<LinearForceModel>(linearStiffnessMatrix(b.mesh, assembler));
  b.system.mass = massMatrix(b.mesh, assembler, MassType::consistent);
  b.system.freeDofs = FreeDofs::fromFixedVertices(b.mesh.numVertices(), b.mesh.vertexSet("root"));
  const std::vector<int> end = b.mesh.vertexSet("xmax");
  b.system.externalForce = [end](double, const Eigen::VectorXd&, const Eigen::VectorXd&, Eigen::VectorXd& f) {
    for (int v : end) f[3 * v + 1] -= 0.05;
  };
  return b;
}

std::vector<int> verticesBeyond(const TetMesh& mesh, double x) {
  std::vector<int> out;
  for (int v = 0; v < mesh.numVertices(); ++v)
    if (mesh.restPosition(v).x() >= x - 1e-12) out.push_back(v);
  return out;
}

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  return values[values.size() / 2];
}

/// Median seconds per step() over `steps` steps after `warmup` untimed ones. The set-up
/// (the factorizations of linear models, done by the constructor's setUp()) is not in it:
/// AsyncBackwardEuler::runStats().setupSeconds reports it.
double timePerStep(Integrator& integrator, int warmup, int steps) {
  for (int k = 0; k < warmup; ++k) integrator.step();
  std::vector<double> samples;
  for (int k = 0; k < steps; ++k) {
    Stopwatch watch;
    integrator.step();
    samples.push_back(watch.stop());
  }
  return median(samples);
}

void growthStudy(int cells, int ratio, double hL, int steps) {
  const Bench b = makeBench(cells);
  std::printf("### Cost per large step as S grows (bar of %d tets, %d vertices, m = %d, hL = %g)\n\n",
              b.mesh.numElements(), b.mesh.numVertices(), ratio, hL);
  auto single = [&](double h) {
    auto be = makeIntegrator("backward-euler", b.system, h);
    return timePerStep(*be, 3, steps);
  };
  const double singleL = single(hL);
  const double singleS = single(hL / ratio) * ratio;  // m small steps per large step
  std::printf("single-rate backward Euler: %.3f ms per step at hL, %.3f ms per large step at hS (%d steps)\n\n",
              1e3 * singleL, 1e3 * singleS, ratio);
  std::printf(
      "| S (fraction of length) | S vertices | interface DOFs | async ms/step | solves-only floor ms | "
      "async / floor | async / single-rate hL | async / single-rate hS | setup s |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|\n");
  for (double fraction : {0.05, 0.1, 0.25, 0.5, 0.75, 1.0}) {
    std::vector<AsyncRegion> regions{{"S", verticesBeyond(b.mesh, 1.0 - fraction), ratio}};
    AsyncBackwardEuler async(b.mesh, b.system, hL, regions);
    const double t = timePerStep(async, 3, steps);
    const double setup = async.runStats().setupSeconds;
    const double floor = async.solveFloorSeconds(steps);
    std::printf("| %.2f | %zu | %zu | %.3f | %.3f | %.2f | %.2f | %.2f | %.2f |\n", fraction,
                regions[0].vertices.size(), async.partition().interfaceDofs(0).size(), 1e3 * t, 1e3 * floor, t / floor,
                t / singleL, t / singleS, setup);
  }
  std::printf("\n");
}

void ratioStudy(int cells, double hL, int steps, int maxNaiveRatio) {
  const Bench b = makeBench(cells);
  const std::vector<int> tip = verticesBeyond(b.mesh, 0.9);
  std::printf("### Structured against naive as m grows (bar of %d tets, |S| = %zu vertices, hL = %g)\n\n",
              b.mesh.numElements(), tip.size(), hL);
  std::printf(
      "| m | structured ms/step | naive ms/step | naive / structured | structured setup s | naive setup s | "
      "naive factor nnz | structured factor nnz |\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  for (int m : {2, 4, 8, 16, 32, 64}) {
    std::vector<AsyncRegion> regions{{"tip", tip, m}};
    AsyncBackwardEuler structured(b.mesh, b.system, hL, regions);
    const double ts = timePerStep(structured, 2, steps);
    const double setupStructured = structured.runStats().setupSeconds;
    double setupNaive = 0;
    if (m > maxNaiveRatio) {
      std::printf("| %d | %.3f | (skipped: m > %d) | | %.2f | | | %lld |\n", m, 1e3 * ts, maxNaiveRatio,
                  setupStructured, structured.factorNonZeros());
      continue;
    }
    AsyncOptions naiveOptions;
    naiveOptions.method = AsyncSolveMethod::naive;
    AsyncBackwardEuler naive(b.mesh, b.system, hL, regions, naiveOptions);
    double tn = 0;
    try {
      tn = timePerStep(naive, 2, steps);
      setupNaive = naive.runStats().setupSeconds;
    } catch (const asyncfem::Error& e) {
      std::printf("| %d | %.3f | failed: %s | | %.2f | | | %lld |\n", m, 1e3 * ts, e.what(), setupStructured,
                  structured.factorNonZeros());
      continue;
    }
    std::printf("| %d | %.3f | %.3f | %.1f | %.2f | %.2f | %lld | %lld |\n", m, 1e3 * ts, 1e3 * tn, tn / ts,
                setupStructured, setupNaive, naive.factorNonZeros(), structured.factorNonZeros());
  }
  std::printf("\n");
}

void schurStudy(int cells, int ratio, double hL, int steps) {
  const Bench b = makeBench(cells);
  std::printf(
      "### H^{LL*}: exact low-rank (Cholesky of A^L + capacitance), exact LU (UMFPACK), symmetric "
      "approximation (CHOLMOD) (bar of %d tets, m = %d, hL = %g, %d steps)\n\n",
      b.mesh.numElements(), ratio, hL, steps);
  std::printf(
      "| S (fraction) | low-rank ms/step | LU ms/step | symmetric ms/step | low-rank setup s | LU setup s | "
      "symmetric setup s | asymmetry of the correction | max relative trajectory difference, symmetric vs exact |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|\n");
  for (double fraction : {0.1, 0.25, 0.5}) {
    std::vector<AsyncRegion> regions{{"S", verticesBeyond(b.mesh, 1.0 - fraction), ratio}};
    AsyncOptions symmetricOptions;
    symmetricOptions.schur = SchurMode::symmetric;
    AsyncBackwardEuler exact(b.mesh, b.system, hL, regions);
    AsyncBackwardEuler symmetric(b.mesh, b.system, hL, regions, symmetricOptions);
    AsyncOptions luOptions;
    luOptions.schur = SchurMode::lu;
    AsyncBackwardEuler lu(b.mesh, b.system, hL, regions, luOptions);
    const double tl = timePerStep(lu, 1, steps);
    const double setupLu = lu.runStats().setupSeconds;
    const double setupExact = exact.runStats().setupSeconds, setupSymmetric = symmetric.runStats().setupSeconds;
    std::vector<double> te, tsym;
    double worst = 0;
    for (int k = 0; k < steps; ++k) {
      Stopwatch a;
      exact.step();
      te.push_back(a.stop());
      Stopwatch c;
      symmetric.step();
      tsym.push_back(c.stop());
      const double scale = std::max(exact.displacement().lpNorm<Eigen::Infinity>(), 1e-300);
      worst = std::max(worst, (exact.displacement() - symmetric.displacement()).lpNorm<Eigen::Infinity>() / scale);
    }
    std::printf("| %.2f | %.3f | %.3f | %.3f | %.2f | %.2f | %.2f | %.2e | %.2e |\n", fraction, 1e3 * median(te),
                1e3 * tl, 1e3 * median(tsym), setupExact, setupLu, setupSymmetric, exact.schurAsymmetry(), worst);
  }
  std::printf("\n");
}

/// A corotational scenario: the mesh, its system, the fast region and the time at which the
/// motion is free (after the pull is released or after the first impact).
struct Scenario {
  std::string name;
  TetMesh mesh;
  DynamicSystem system;
  std::vector<int> fast;
  double freeFrom = 0.0;
  double contactStiffness = 0.0;  ///< penalty k of the ground (0: no contact)
};

Scenario corotationalBeam(int cells) {
  Scenario s;
  s.name = "beam (pulled 0.2 s, released)";
  BeamSpec spec;
  spec.cellsAlongLength = cells;
  s.mesh = makeBeamMesh(spec);
  MatrixAssembler assembler(s.mesh);
  s.system.forceModel = std::make_shared<CorotationalLinearFEM>(s.mesh, TangentKind::simple);
  s.system.mass = massMatrix(s.mesh, assembler, MassType::consistent);
  s.system.freeDofs = FreeDofs::fromFixedVertices(s.mesh.numVertices(), s.mesh.vertexSet("root"));
  const std::vector<int> tip = s.mesh.vertexSet("tip");
  s.system.externalForce = [tip](double t, const Eigen::VectorXd&, const Eigen::VectorXd&, Eigen::VectorXd& f) {
    if (t > 0.2) return;
    for (int v : tip) f[3 * v + 1] -= 60.0 / static_cast<double>(tip.size());
  };
  s.fast = tip;
  s.freeFrom = 0.2;
  return s;
}

/// The bar both drop scenarios use: soft body, stiff and light last quarter ("stiff").
BoxMeshSpec dropBarSpec(int cells) {
  BoxMeshSpec spec;
  spec.size = Eigen::Vector3d(0.4, 0.1, 0.1);
  spec.cells = Eigen::Vector3i(std::max(4, cells / 2), 2, 2);
  spec.material = Material{"soft", 1000.0, 2e5, 0.4};
  spec.regions.push_back(
      {"stiff", Eigen::Vector3d(0.3, -1, -1), Eigen::Vector3d(1, 1, 1), Material{"stiff", 300.0, 1e7, 0.3}});
  return spec;
}

/// Corotational FEM, consistent mass, no fixed DOF, gravity and ground contact (y = 0) for
/// the scenario's mesh; the stiff quarter is the fast region. contactStiffness(lumped
/// masses) gives the penalty stiffness.
void makeDropSystem(Scenario& s, PenaltyContactParameters contact,
                    const std::function<double(const Eigen::VectorXd&)>& contactStiffness) {
  MatrixAssembler assembler(s.mesh);
  s.system.forceModel = std::make_shared<CorotationalLinearFEM>(s.mesh, TangentKind::simple);
  s.system.mass = massMatrix(s.mesh, assembler, MassType::consistent);
  s.system.freeDofs = FreeDofs(s.mesh.numDofs(), {});
  const Eigen::VectorXd gravity = s.system.mass * Eigen::Vector3d(0, -9.81, 0).replicate(s.mesh.numVertices(), 1);
  contact.stiffness = contactStiffness(s.system.mass * Eigen::VectorXd::Ones(s.system.mass.cols()));
  s.contactStiffness = contact.stiffness;
  auto ground = std::make_shared<PenaltyContact>(s.mesh.restPositions(), std::vector<ContactPlane>{ContactPlane{}},
                                                 std::vector<ContactSphere>{}, contact);
  s.system.externalForce = [gravity, ground](double, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                                             Eigen::VectorXd& f) {
    f += gravity;
    ground->addForces(u, v, f);
  };
  s.fast = s.mesh.vertexSet("stiff");
  s.freeFrom = 0.1;  // falling 0.05 m takes 0.1 s
}

Scenario droppedBody(int cells) {
  Scenario s;
  s.name = "dropped bar with a stiff end (ground contact)";
  BoxMeshSpec spec = dropBarSpec(cells);
  spec.origin = Eigen::Vector3d(0.0, 0.05, 0.0);
  s.mesh = makeBoxMesh(spec);
  PenaltyContactParameters contact;
  contact.damping = 5.0;
  makeDropSystem(s, contact, [](const Eigen::VectorXd&) { return 5e3; });
  return s;
}

/// The contact study's scene: the dropped bar tilted by 25 degrees so that its stiff end
/// lands first, with a penalty stiffness chosen from the lightest vertex so that the
/// contact spring is resolved by the small step (omega hS = 0.5) but not by the large one
/// (omega hL = 0.5 m): the regime substepStatePrediction is meant for. Frictionless, no contact
/// damping, so energy changes come from the integrators alone.
Scenario tiltedDrop(int cells, double hS) {
  Scenario s;
  s.name = "bar tilted 25 degrees, stiff end first";
  const TetMesh box = makeBoxMesh(dropBarSpec(cells));
  const double angle = -25.0 * 3.14159265358979323846 / 180.0;
  Eigen::Matrix3Xd positions =
      Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()).toRotationMatrix() * box.restPositions();
  positions.row(1).array() += 0.05 - positions.row(1).minCoeff();  // lowest point 5 cm above the ground
  s.mesh = TetMesh(positions, box.elements(), box.materials(), box.elementMaterials());
  for (const auto& [name, members] : box.vertexSets()) s.mesh.setVertexSet(name, members);
  for (const auto& [name, members] : box.elementSets()) s.mesh.setElementSet(name, members);
  makeDropSystem(s, PenaltyContactParameters{},
                 [hS](const Eigen::VectorXd& lumped) { return lumped.minCoeff() * (0.5 / hS) * (0.5 / hS); });
  return s;
}

/// Mean over the fast vertices of |v - mean(v)|^2: the fast region's vibration without the
/// rigid motion it shares with the body.
double fastVibrationSquared(const Integrator& integrator, const std::vector<int>& fast) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int v : fast) mean += integrator.velocity().segment<3>(3 * v);
  mean /= static_cast<double>(fast.size());
  double sum = 0.0;
  for (int v : fast) sum += (integrator.velocity().segment<3>(3 * v) - mean).squaredNorm();
  return sum / static_cast<double>(fast.size());
}

/// RMS over the frames after `freeFrom` of the fast region's velocity relative to its own
/// mean velocity (its vibration, which a large step damps away, without the rigid swing
/// it shares with the body), and the time split of a run of `duration`.
struct CorotationalRun {
  double rmsVelocity = 0.0;
  double secondsPerFrame = 0.0;
  IntegratorStats stats;
  double zSeconds = 0.0;
  int frames = 0;
};

CorotationalRun runCorotational(Integrator& integrator, const Scenario& s, double frameInterval, double duration) {
  CorotationalRun run;
  const int frames = static_cast<int>(std::lround(duration / frameInterval));
  const int stepsPerFrame = std::max(1, static_cast<int>(std::lround(frameInterval / integrator.timestep())));
  double sum = 0.0;
  int counted = 0;
  Stopwatch watch;
  for (int f = 0; f < frames; ++f) {
    for (int k = 0; k < stepsPerFrame; ++k) integrator.step();
    if (integrator.time() > s.freeFrom) {
      sum += fastVibrationSquared(integrator, s.fast);
      ++counted;
    }
  }
  run.secondsPerFrame = watch.stop() / frames;
  run.rmsVelocity = std::sqrt(sum / std::max(1, counted));
  run.stats = integrator.stats();
  run.frames = frames;
  return run;
}

void corotationalStudy(int cells, int ratio, double hL) {
  const double frameInterval = 1.0 / 60.0, duration = 1.0;
  for (const Scenario& s : {corotationalBeam(cells), droppedBody(cells)}) {
    std::printf("### Corotational: %s (%d tets, |S| = %zu vertices, hL = %g, m = %d, 1 s at 60 frames/s)\n\n",
                s.name.c_str(), s.mesh.numElements(), s.fast.size(), hL, ratio);
    AsyncBackwardEuler async(s.mesh, s.system, hL, {{"S", s.fast, ratio}});
    const CorotationalRun a = runCorotational(async, s, frameInterval, duration);
    auto single = [&](double h) {
      auto be = makeIntegrator("backward-euler", s.system, h);
      return runCorotational(*be, s, frameInterval, duration);
    };
    const CorotationalRun large = single(hL);
    const CorotationalRun small = single(hL / ratio);
    // Equal cost: the single-rate step whose cost per frame matches async's (a divisor of hL).
    const int k = std::max(1, static_cast<int>(std::lround(a.secondsPerFrame / large.secondsPerFrame)));
    const CorotationalRun equal = single(hL / k);
    std::printf(
        "| run | ms/frame | RMS vibration velocity of S after release | retained vs hS run |\n|---|---|---|---|\n");
    auto row = [&](const char* label, const CorotationalRun& r) {
      std::printf("| %s | %.2f | %.4g | %.2f |\n", label, 1e3 * r.secondsPerFrame, r.rmsVelocity,
                  r.rmsVelocity / small.rmsVelocity);
    };
    row("async (hL, S at hL/m)", a);
    row("single-rate at hL", large);
    const std::string equalLabel = "single-rate at hL/" + std::to_string(k) + " (equal cost)";
    row(equalLabel.c_str(), equal);
    row("single-rate at hS = hL/m", small);
    const double f = a.frames;
    const IntegratorStats& st = a.stats;
    std::printf(
        "\nasync time per frame: forces %.2f ms, refactorizations %.2f ms, Z columns %.2f ms, "
        "assembly %.2f ms, solves %.2f ms (%lld factorizations)\n\n",
        1e3 * st.forceSeconds / f, 1e3 * (st.factorizationSeconds - async.zColumnSeconds()) / f,
        1e3 * async.zColumnSeconds() / f, 1e3 * st.assemblySeconds / f, 1e3 * st.solveSeconds / f, st.factorizations);
  }
}

/// What testing S's contacts at every substep (AsyncOptions::Contact::substepStatePrediction)
/// changes and costs, on the dropped bar whose stiff end lands on the ground: penetration
/// of the fast region, its vibration after the impact and the energy after the impact,
/// against contact once per large step and against single-rate backward Euler.
void contactStudy(int cells, int ratio, double hL) {
  const double frameInterval = 1.0 / 60.0, duration = 1.0;
  const Scenario s = tiltedDrop(cells, hL / ratio);
  std::printf(
      "### Contact at every substep: %s (%d tets, |S| = %zu vertices, hL = %g, m = %d, 1 s at 60 "
      "frames/s, ground y = 0)\n\n",
      s.name.c_str(), s.mesh.numElements(), s.fast.size(), hL, ratio);
  struct ContactRun {
    double secondsPerFrame = 0.0, maxPenetrationS = 0.0, maxPenetrationAll = 0.0, rmsVelocity = 0.0;
    double energyAfterImpact = 0.0, finalEnergy = 0.0;
  };
  const Eigen::Matrix3Xd& rest = s.mesh.restPositions();
  // Kinetic + elastic + gravitational energy (ground penalty energy left out: it is what the
  // penetration column shows).
  auto energy = [&](const Integrator& integrator) {
    const Eigen::VectorXd& u = integrator.displacement();
    double height = 0.0;
    const Eigen::VectorXd lumped = s.system.mass * Eigen::VectorXd::Ones(u.size());
    for (int v = 0; v < s.mesh.numVertices(); ++v) height += lumped[3 * v + 1] * 9.81 * (rest(1, v) + u[3 * v + 1]);
    return integrator.mechanicalEnergy() + height;
  };
  auto measure = [&](Integrator& integrator) {
    ContactRun run;
    const int frames = static_cast<int>(std::lround(duration / frameInterval));
    const int stepsPerFrame = std::max(1, static_cast<int>(std::lround(frameInterval / integrator.timestep())));
    std::vector<char> inS(static_cast<std::size_t>(s.mesh.numVertices()), 0);
    for (int v : s.fast) inS[static_cast<std::size_t>(v)] = 1;
    double sum = 0.0, seconds = 0.0;
    int counted = 0;
    bool impactSeen = false;
    for (int f = 0; f < frames; ++f) {
      for (int k = 0; k < stepsPerFrame; ++k) {
        Stopwatch watch;
        integrator.step();
        seconds += watch.stop();
        const Eigen::VectorXd& u = integrator.displacement();
        for (int v = 0; v < s.mesh.numVertices(); ++v) {
          const double depth = std::max(0.0, -(rest(1, v) + u[3 * v + 1]));
          run.maxPenetrationAll = std::max(run.maxPenetrationAll, depth);
          if (inS[static_cast<std::size_t>(v)]) run.maxPenetrationS = std::max(run.maxPenetrationS, depth);
        }
      }
      if (integrator.time() > s.freeFrom) {
        if (!impactSeen) run.energyAfterImpact = energy(integrator);
        impactSeen = true;
        sum += fastVibrationSquared(integrator, s.fast);
        ++counted;
      }
    }
    run.secondsPerFrame = seconds / frames;
    run.rmsVelocity = std::sqrt(sum / std::max(1, counted));
    run.finalEnergy = energy(integrator);
    return run;
  };
  AsyncBackwardEuler once(s.mesh, s.system, hL, {{"S", s.fast, ratio}});
  const double initialEnergy = energy(once);
  AsyncOptions substepOptions;
  substepOptions.contact.substepStatePrediction = true;
  AsyncBackwardEuler substep(s.mesh, s.system, hL, {{"S", s.fast, ratio}}, substepOptions);
  const ContactRun a = measure(once);
  const ContactRun b = measure(substep);
  auto be = [&](double h) {
    auto integrator = makeIntegrator("backward-euler", s.system, h);
    return measure(*integrator);
  };
  const ContactRun large = be(hL), small = be(hL / ratio);
  std::printf(
      "| run | ms/frame | max penetration of S (m) | max penetration, all (m) | RMS vibration velocity of S "
      "after impact | energy at first frame after impact (J) | energy at 1 s (J) |\n");
  std::printf("|---|---|---|---|---|---|---|\n");
  auto row = [](const char* label, const ContactRun& r) {
    std::printf("| %s | %.2f | %.3g | %.3g | %.4g | %.4g | %.4g |\n", label, 1e3 * r.secondsPerFrame, r.maxPenetrationS,
                r.maxPenetrationAll, r.rmsVelocity, r.energyAfterImpact, r.finalEnergy);
  };
  row("async, contact once per large step", a);
  row("async, S contact at every substep", b);
  row("single-rate at hL", large);
  row("single-rate at hS = hL/m", small);
  // omega h of the penalty spring on the lightest and on the median vertex (every vertex of
  // this 2 x 2 cross-section bar but a line of interior ones is on the boundary): sceneIO
  // warns when the median one exceeds 2.
  Eigen::VectorXd lumped = s.system.mass * Eigen::VectorXd::Ones(s.system.mass.cols());
  std::sort(lumped.begin(), lumped.end());
  const double lightest = std::sqrt(s.contactStiffness / lumped[0]);
  const double median = std::sqrt(s.contactStiffness / lumped[lumped.size() / 2]);
  std::printf(
      "\nEnergy (kinetic + elastic + gravity) at t = 0: %.4g J. Penalty stiffness %.4g N/m per vertex, no "
      "contact damping or friction; omega hL = %.2f (lightest vertex), %.2f (median vertex); omega hS = %.2f, "
      "%.2f.\n\n",
      initialEnergy, s.contactStiffness, lightest * hL, median * hL, lightest * hL / ratio, median * hL / ratio);
}

/// A scene for the steady-state study: a file, or "dragon:H:SET:M:HL", the procedural
/// dragon meshed at spacing H (models/README.md) with the vertex set SET as its one fast
/// region at ratio M and the large step HL, everything else as models/dragon/dragon.json.
Scene steadyScene(const std::string& spec, bool corotational) {
  Scene scene;
  if (spec.rfind("dragon:", 0) == 0) {
    std::vector<std::string> parts;
    std::size_t from = 0;
    for (std::size_t at; (at = spec.find(':', from)) != std::string::npos; from = at + 1)
      parts.push_back(spec.substr(from, at - from));
    parts.push_back(spec.substr(from));
    if (parts.size() != 5) throw ValidationError("--scenes: expected dragon:SPACING:SET:M:HL, got " + spec);
    const double spacing = std::stod(parts[1]);
    const std::string path = "/tmp/benchmarkAsync-dragon-" + parts[1] + ".veg";
    if (!std::ifstream(path)) writeVeg(path, makeExampleModel(ExampleModel::Dragon, spacing));
    scene = loadScene("models/dragon/dragon.json");
    scene.mesh.file = path;
    scene.integrator.options["regions"] =
        nlohmann::json::array({{{"name", parts[2]}, {"ratio", std::stoi(parts[3])}, {"vertexSets", {parts[2]}}}});
    const double hL = std::stod(parts[4]);
    overrideFrameTiming(scene, {.timestep = hL, .frameRate = 1.0 / hL});  // one frame per large step
    scene.sourceName = "dragon (spacing " + parts[1] + ", S = " + parts[2] + ")";
  } else {
    scene = loadScene(spec);
  }
  if (corotational) scene.forceModel = Scene::ForceModelKind::corotational;
  return scene;
}

/// The asynchronous integrator a scene built (ValidationError naming spec for another one).
AsyncBackwardEuler& asyncOf(Simulation& simulation, const std::string& spec) {
  auto* async = dynamic_cast<AsyncBackwardEuler*>(simulation.integrator.get());
  if (async == nullptr) throw ValidationError(spec + ": the scene's integrator is not async");
  return *async;
}

/// Large steps per block when the corotational steady study times async and single-rate
/// at hS in turn.
constexpr int kInterleavedSteps = 10;

struct SteadyRow {
  std::string name;
  int vertices = 0, fastVertices = 0, interfaceDofs = 0, ratio = 1;
  double hL = 0;
  double setupZ = 0, setupSchur = 0;
  double setup = 0, asyncStep = 0, asyncMeanStep = 0, singleSetup = 0, singleStep = 0, singleStepHS = 0;
  // Wall time per step over all timed steps (the mean): steps that rebuild or refactor are
  // part of the cost, which a median leaves out.
  double asyncMeanWall = 0, singleMeanHS = 0;
  RegionProposalCost model;  // the proposed regions' cost model of the same partition
};

/// Steady state: per scene, the async step (median wall, and the integrator's own mean of
/// its steady steps) against one single-rate backward Euler step at hL on the same system;
/// set-up against single-rate steps at hL. With `only`, one configuration and no table
/// (for callgrind). Corotational: the async large step against m corotational single-rate
/// steps at hS, both as the mean wall time of all timed steps (the lagged factor's rebuilds
/// and single-rate's refactorizations included), the medians beside them, timed in turn in
/// blocks of kInterleavedSteps large steps.
void steadyStudy(const std::vector<std::string>& scenes, int steps, bool corotational, const std::string& only,
                 bool collectFirst, bool rebuildSchur, int laggedIterations, bool unturned) {
  std::vector<SteadyRow> rows;
  for (const std::string& spec : scenes) {
    const Scene scene = steadyScene(spec, corotational);
    Simulation simulation = buildSimulation(scene);
    auto* async = &asyncOf(simulation, spec);
    std::unique_ptr<AsyncBackwardEuler> rebuilt;
    if (rebuildSchur || laggedIterations > 0 || unturned) {
      // The same scene with AsyncOptions::KeptFactors::laggedSchur off (Z and H^{LL*} every large step),
      // with another iteration limit for the lagged factor, or with the lagged factor not
      // turned with the body.
      AsyncOptions options = async->options();
      options.keptFactors.laggedSchur = !rebuildSchur;
      options.keptFactors.laggedSchurRotation = !unturned;
      if (laggedIterations > 0) options.keptFactors.laggedSchurIterations = laggedIterations;
      std::vector<AsyncRegion> regions;
      for (int i = 0; i < async->partition().numRegions(); ++i) regions.push_back(async->partition().region(i));
      rebuilt =
          std::make_unique<AsyncBackwardEuler>(*simulation.mesh, async->system(), async->timestep(), regions, options);
      async = rebuilt.get();
    }
    SteadyRow row;
    row.name = scene.sourceName;
    row.vertices = simulation.mesh->numVertices();
    row.hL = async->timestep();
    const RegionPartition& partition = async->partition();
    for (int i = 0; i < partition.numRegions(); ++i) {
      row.fastVertices += static_cast<int>(partition.region(i).vertices.size());
      row.ratio = std::max(row.ratio, partition.ratio(i));
    }
    row.interfaceDofs = async->runStats().interfaceDofs;
    {
      std::vector<AsyncRegion> regions;
      for (int i = 0; i < partition.numRegions(); ++i) regions.push_back(partition.region(i));
      row.model = estimateAsyncCost(*simulation.mesh, simulation.problem->freeDofs(), regions, corotational);
    }
    const DynamicSystem system = async->system();
    // Collected for callgrind: the first step (set-up included) with --first, else the
    // timed steady steps.
    const auto warmUp = [&](Integrator& integrator, double* setup) {
      Stopwatch first;
      if (!only.empty() && collectFirst) ASYNCFEM_COLLECT_ON();
      integrator.step();
      if (!only.empty() && collectFirst) ASYNCFEM_COLLECT_OFF();
      if (setup) *setup = first.stop();
      integrator.step();
    };
    const auto timeSteps = [&](Integrator& integrator, int count, std::vector<double>& samples) {
      if (!only.empty() && !collectFirst) ASYNCFEM_COLLECT_ON();
      for (int k = 0; k < count; ++k) {
        Stopwatch watch;
        integrator.step();
        samples.push_back(watch.stop());
      }
      if (!only.empty() && !collectFirst) ASYNCFEM_COLLECT_OFF();
    };
    const auto mean = [](const std::vector<double>& samples) {
      return std::accumulate(samples.begin(), samples.end(), 0.0) / static_cast<double>(samples.size());
    };
    const auto measure = [&](Integrator& integrator, double* setup, double* meanStep = nullptr) {
      warmUp(integrator, setup);
      std::vector<double> samples;
      timeSteps(integrator, steps, samples);
      if (meanStep) *meanStep = mean(samples);
      return median(samples);
    };
    // Corotational, whole table: the async steps and single-rate's at hS in turn, blocks of
    // kInterleavedSteps large steps each, so that a change of the shared machine's speed
    // during the run weighs on both sides of the ratio alike.
    const bool interleaved = only.empty() && corotational;
    std::unique_ptr<Integrator> small;
    std::vector<double> asyncSamples, smallSamples;
    if (interleaved) small = makeIntegrator("backward-euler", system, row.hL / row.ratio);
    if (only.empty() || only == "async") {
      if (!only.empty() && collectFirst) {
        // The set-up runs in the constructor (setUp()); collect it once more, as it is.
        ASYNCFEM_COLLECT_ON();
        async->setUp(async->partition());
        ASYNCFEM_COLLECT_OFF();
      }
      if (interleaved) {
        warmUp(*async, &row.setup);
        warmUp(*small, nullptr);
        for (int done = 0; done < steps; done += kInterleavedSteps) {
          const int block = std::min(kInterleavedSteps, steps - done);
          timeSteps(*async, block, asyncSamples);
          timeSteps(*small, block * row.ratio, smallSamples);
        }
        row.asyncStep = median(asyncSamples);
        row.asyncMeanWall = mean(asyncSamples);
        row.singleStepHS = median(smallSamples) * row.ratio;
        row.singleMeanHS = mean(smallSamples) * row.ratio;
      } else {
        row.asyncStep = measure(*async, &row.setup, &row.asyncMeanWall);
      }
      row.asyncMeanStep =
          corotational ? async->runStats().meanStepWithRebuildSeconds() : async->runStats().meanStepSeconds();
      row.setup = async->runStats().setupSeconds;
      row.setupZ = async->runStats().setupZSeconds;
      row.setupSchur = async->runStats().setupSchurSeconds;
      if (corotational) {
        const AsyncRunStats& stats = async->runStats();
        std::fprintf(stderr, "%s: %lld steps, %lld lagged, %lld rebuilds, %lld Schur iterations, %lld refreshes\n",
                     scene.sourceName.c_str(), stats.steps, stats.laggedSteps, stats.rebuilds, stats.schurIterations,
                     stats.laggedRefreshes);
      }
    }
    if (only.empty() || only == "single") {
      // Single-rate factors in its constructor: its set-up is construction + first step.
      Stopwatch construction;
      if (!only.empty() && collectFirst) ASYNCFEM_COLLECT_ON();
      auto single = makeIntegrator("backward-euler", system, row.hL);
      if (!only.empty() && collectFirst) ASYNCFEM_COLLECT_OFF();
      const double constructionSeconds = construction.stop();
      row.singleStep = measure(*single, &row.singleSetup);
      row.singleSetup += constructionSeconds;
    }
    if (only == "single-hs") {
      auto hs = makeIntegrator("backward-euler", system, row.hL / row.ratio);
      row.singleStepHS = measure(*hs, nullptr, &row.singleMeanHS) * row.ratio;
      row.singleMeanHS *= row.ratio;
    }
    if (!only.empty()) {
      const double perStep = only == "async" ? row.asyncStep : only == "single" ? row.singleStep : row.singleStepHS;
      const double mean = only == "async" ? row.asyncMeanWall : only == "single-hs" ? row.singleMeanHS : 0.0;
      std::printf("%s: %s, %d steps collected, m = %d: %.3f ms per step (median; single-hs: per m steps), mean %.3f\n",
                  row.name.c_str(), only.c_str(), steps, row.ratio, 1e3 * perStep, 1e3 * mean);
      continue;
    }
    rows.push_back(row);
  }
  if (!only.empty()) return;
  std::printf("### Steady state: async against single-rate backward Euler (%s forces, %d timed steps)\n\n",
              corotational ? "corotational" : "linear", steps);
  if (!corotational) {
    std::printf(
        "| scene | vertices | S vertices (%%) | interface DOFs | m | hL | async ms/step | single-rate hL ms/step | "
        "ratio | cost model ratio | async set-up ms (Z, H^{LL*}) | single-rate set-up ms | set-up / single-rate "
        "step | cost model set-up ratio |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (const SteadyRow& r : rows) {
      // The model's single-rate side is m steps at hL / m; one of them costs as one at hL.
      const double modelStep = r.model.singleRateFlops / r.model.singleRateSubsteps;
      std::printf(
          "| %s | %d | %d (%.1f%%) | %d | %d | %.4g | %.3f | %.3f | %.2f | %.2f | %.1f (%.1f, %.1f) | %.1f | %.1f | "
          "%.1f "
          "|\n",
          r.name.c_str(), r.vertices, r.fastVertices, 100.0 * r.fastVertices / r.vertices, r.interfaceDofs, r.ratio,
          r.hL, 1e3 * r.asyncStep, 1e3 * r.singleStep, r.asyncStep / r.singleStep, r.model.asyncFlops / modelStep,
          1e3 * r.setup, 1e3 * r.setupZ, 1e3 * r.setupSchur, 1e3 * r.singleSetup, r.setup / r.singleStep,
          r.model.asyncSetupFlops / modelStep);
    }
    std::printf(
        "\nCost model: the flops proposed regions estimate (RegionProposalCost, from CHOLMOD's symbolic analysis); "
        "its ratios use the same denominators as the measured ones.\n");
  } else {
    std::printf("%s",
                rebuildSchur
                    ? "With AsyncOptions::KeptFactors::laggedSchur off (Z and H^{LL*} rebuilt every large step).\n\n"
                    : "With AsyncOptions::KeptFactors::laggedSchur (the default).\n\n");
    std::printf(
        "Mean wall time of the %d timed steps (rebuilds and refactorizations included); medians in parentheses. "
        "Async and single-rate at hS timed in turn, %d large steps at a time.\n\n"
        "| scene | vertices | S vertices (%%) | interface DOFs | m | async ms/large step | single-rate hL ms/step | "
        "single-rate hS ms per hL | async / single-rate hS (medians) | cost model ratio | async set-up ms "
        "|\n|---|---|---|---|---|---|---|---|---|---|---|\n",
        steps, kInterleavedSteps);
    for (const SteadyRow& r : rows)
      std::printf(
          "| %s | %d | %d (%.1f%%) | %d | %d | %.3f (%.3f) | %.3f | %.3f (%.3f) | %.2f (%.2f) | %.2f | %.1f |\n",
          r.name.c_str(), r.vertices, r.fastVertices, 100.0 * r.fastVertices / r.vertices, r.interfaceDofs, r.ratio,
          1e3 * r.asyncMeanWall, 1e3 * r.asyncStep, 1e3 * r.singleStep, 1e3 * r.singleMeanHS, 1e3 * r.singleStepHS,
          r.asyncMeanWall / r.singleMeanHS, r.asyncStep / r.singleStepHS, r.model.ratio(), 1e3 * r.setup);
  }
  std::printf("\n");
}

/// Z by substitution against Z from the regions' modes (AsyncOptions::zSolve): per scene,
/// the set-up (and its Z part) of each, constructed in turn `repeats` times (medians), and
/// single-rate backward Euler's set-up (construction and first step: its factorization) at
/// hL in the same run; then both integrators take `steps` steps from the scene's start and
/// the largest relative difference of their displacements is printed (round-off).
void zModesStudy(const std::vector<std::string>& scenes, int repeats, int steps, bool corotational) {
  std::printf(
      "### Z by substitution and from the regions' modes (%s forces, medians of %d set-ups each)\n\n"
      "| scene | vertices | S DOFs | interface DOFs | m | single-rate set-up ms | substitution: set-up ms (Z) "
      "| modes: set-up ms (Z) | Z: substitution / modes | automatic: Z ms (regions from modes) | set-up / "
      "single-rate: substitution, modes, automatic | difference after %d steps |\n"
      "|---|---|---|---|---|---|---|---|---|---|---|---|\n",
      corotational ? "corotational" : "linear", repeats, steps);
  for (const std::string& spec : scenes) {
    const Scene scene = steadyScene(spec, corotational);
    Simulation simulation = buildSimulation(scene);
    const AsyncBackwardEuler* sceneAsync = &asyncOf(simulation, spec);
    std::vector<AsyncRegion> regions;
    int ratio = 1;
    for (int i = 0; i < sceneAsync->partition().numRegions(); ++i) {
      regions.push_back(sceneAsync->partition().region(i));
      ratio = std::max(ratio, sceneAsync->partition().ratio(i));
    }
    const DynamicSystem system = sceneAsync->system();
    const double hL = sceneAsync->timestep();
    std::array<std::vector<double>, 3> setUp, zPart;
    std::vector<double> single;
    std::array<std::unique_ptr<AsyncBackwardEuler>, 3> kept;
    const ZSolve kinds[3] = {ZSolve::substitution, ZSolve::modes, ZSolve::automatic};
    for (int repeat = 0; repeat < repeats; ++repeat) {
      for (int kind = 0; kind < 3; ++kind) {
        AsyncOptions options = sceneAsync->options();
        options.zSolve = kinds[kind];
        auto async = std::make_unique<AsyncBackwardEuler>(*simulation.mesh, system, hL, regions, options);
        setUp[kind].push_back(async->runStats().setupSeconds);
        zPart[kind].push_back(async->runStats().setupZSeconds);
        kept[kind] = std::move(async);
      }
      Stopwatch construction;
      auto singleRate = makeIntegrator("backward-euler", system, hL);
      singleRate->step();
      single.push_back(construction.stop());
    }
    const int automatic = kept[2]->runStats().zModalRegions;
    for (int k = 0; k < steps; ++k)
      for (auto& async : kept) async->step();
    const Eigen::VectorXd& a = kept[0]->displacement();
    const double difference = (kept[1]->displacement() - a).norm() / std::max(a.norm(), 1e-300);
    std::array<double, 3> s{}, z{};
    for (int kind = 0; kind < 3; ++kind) {
      s[kind] = median(setUp[kind]);
      z[kind] = median(zPart[kind]);
    }
    const double base = median(single);
    std::printf(
        "| %s | %d | %d | %d | %d | %.1f | %.1f (%.1f) | %.1f (%.1f) | %.1f | %.1f (%d of %zu) | %.1f, %.1f, %.1f | "
        "%.1e |\n",
        scene.sourceName.c_str(), simulation.mesh->numVertices(), kept[0]->runStats().fastDofs,
        kept[0]->runStats().interfaceDofs, ratio, 1e3 * base, 1e3 * s[0], 1e3 * z[0], 1e3 * s[1], 1e3 * z[1],
        z[0] / z[1], 1e3 * z[2], automatic, regions.size(), s[0] / base, s[1] / base, s[2] / base, difference);
  }
  std::printf("\n");
}

struct SetUpRow {
  std::string name;
  int vertices = 0, fastVertices = 0, interfaceDofs = 0, ratio = 1, movedVertices = 0;
  double singleStep = 0, singleSetup = 0, exactStep = 0;
  // [0] exact set-up, [1] quickSetUp; for the first partition and for the re-partition.
  std::array<double, 2> setup{}, excess{}, repartition{}, repartitionExcess{};
  std::array<long long, 2> quickSteps{}, repartitionQuickSteps{};
};

/// Seconds of each of `count` steps.
std::vector<double> timedSteps(Integrator& integrator, int count) {
  std::vector<double> samples;
  for (int k = 0; k < count; ++k) {
    Stopwatch watch;
    integrator.step();
    samples.push_back(watch.stop());
  }
  return samples;
}

/// Seconds the steps spend beyond `steady` each.
double excessOver(const std::vector<double>& samples, double steady) {
  double excess = 0.0;
  for (double s : samples) excess += s - steady;
  return excess;
}

/// Every region grown by one ring of vertices (a re-partition that moves a few percent).
std::vector<AsyncRegion> grownByOneRing(const TetMesh& mesh, const std::vector<AsyncRegion>& regions) {
  std::vector<AsyncRegion> grown;
  for (const AsyncRegion& region : regions) {
    std::vector<char> marked(static_cast<std::size_t>(mesh.numVertices()), 0);
    for (int v : region.vertices) marked[static_cast<std::size_t>(v)] = 1;
    growByRings(mesh, marked, 1);
    AsyncRegion bigger = region;
    bigger.vertices.clear();
    for (int v = 0; v < mesh.numVertices(); ++v)
      if (marked[static_cast<std::size_t>(v)]) bigger.vertices.push_back(v);
    grown.push_back(bigger);
  }
  return grown;
}

/// Set-up: per scene, the asynchronous integrator with the exact set-up (Z and H^{LL*}) and
/// with AsyncOptions::KeptFactors::quickSetUp (rent-or-buy rule on, as a user runs it): the set-up, then
/// what the next `steps` steps spend beyond the exact integrator's steady step, for the
/// scene's partition and for a re-partition that grows every region by one ring; all in
/// single-rate steps at hL.
void setUpStudy(const std::vector<std::string>& scenes, int steps) {
  std::vector<SetUpRow> rows;
  for (const std::string& spec : scenes) {
    const Scene scene = steadyScene(spec, false);
    Simulation simulation = buildSimulation(scene);
    auto* shipped = dynamic_cast<AsyncBackwardEuler*>(simulation.integrator.get());
    if (shipped == nullptr) throw ValidationError(spec + ": the scene's integrator is not async");
    const DynamicSystem system = shipped->system();
    const TetMesh& mesh = *simulation.mesh;
    std::vector<AsyncRegion> regions;
    for (int i = 0; i < shipped->partition().numRegions(); ++i) regions.push_back(shipped->partition().region(i));
    const std::vector<AsyncRegion> grown = grownByOneRing(mesh, regions);
    SetUpRow row;
    row.name = scene.sourceName;
    row.vertices = mesh.numVertices();
    row.interfaceDofs = shipped->runStats().interfaceDofs;
    row.fastVertices = shipped->runStats().fastDofs / 3;
    for (const AsyncRegion& region : regions) row.ratio = std::max(row.ratio, region.ratio);
    const double hL = shipped->timestep();
    {
      Stopwatch construction;
      auto single = makeIntegrator("backward-euler", system, hL);
      single->step();
      row.singleSetup = construction.stop();
      row.singleStep = median(timedSteps(*single, steps));
    }
    const RegionPartition next(mesh, system.freeDofs, grown);
    for (std::size_t v = 0; v < next.vertexRegion().size(); ++v)
      if ((next.vertexRegion()[v] >= 0) != (shipped->partition().vertexRegion()[v] >= 0)) ++row.movedVertices;
    for (int kind = 0; kind < 2; ++kind) {
      AsyncOptions options = shipped->options();
      options.keptFactors.quickSetUp = kind == 1;
      Stopwatch construction;
      AsyncBackwardEuler async(mesh, system, hL, regions, options);
      row.setup[kind] = construction.stop();
      const std::vector<double> first = timedSteps(async, steps);
      if (kind == 0) row.exactStep = median(first);
      row.excess[kind] = excessOver(first, row.exactStep);
      row.quickSteps[kind] = async.runStats().quickSteps;
      Stopwatch repartition;
      async.setUp(next);
      row.repartition[kind] = repartition.stop();
      const long long before = async.runStats().quickSteps;
      row.repartitionExcess[kind] = excessOver(timedSteps(async, steps), row.exactStep);
      row.repartitionQuickSteps[kind] = async.runStats().quickSteps - before;
    }
    rows.push_back(row);
  }
  std::printf(
      "### Set-up: exact (Z and H^{LL*}) against quickSetUp, in single-rate steps at hL (linear forces, %d steps "
      "after each set-up)\n\n",
      steps);
  std::printf(
      "| scene | vertices | S vertices | interface DOFs | m | single-rate ms/step | single-rate set-up | exact: set-up "
      "+ excess | quick: set-up + excess (steps on the quick path) | re-partition +1 ring: vertices moved | exact: "
      "set-up + excess | quick: set-up + excess (quick steps) |\n"
      "|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const SetUpRow& r : rows) {
    const double u = r.singleStep;
    std::printf(
        "| %s | %d | %d | %d | %d | %.3f | %.1f | %.1f + %.1f | %.1f + %.1f (%lld) | %d (%.1f%%) | %.1f + %.1f | "
        "%.1f + %.1f (%lld) |\n",
        r.name.c_str(), r.vertices, r.fastVertices, r.interfaceDofs, r.ratio, 1e3 * u, r.singleSetup / u,
        r.setup[0] / u, r.excess[0] / u, r.setup[1] / u, r.excess[1] / u, r.quickSteps[1], r.movedVertices,
        100.0 * r.movedVertices / r.vertices, r.repartition[0] / u, r.repartitionExcess[0] / u, r.repartition[1] / u,
        r.repartitionExcess[1] / u, r.repartitionQuickSteps[1]);
  }
  std::printf(
      "\nSingle-rate set-up: its construction and first step. Excess: what the %d steps after the set-up spend beyond "
      "as many steady steps of the exact integrator (the exact one's own excess is its first steps' noise); for the "
      "quick set-up it includes the rebuild the rent-or-buy rule may decide.\n\n",
      steps);
}

}  // namespace

int main(int argc, char** argv) {
  asyncfem::preferPassiveThreadWaiting(argv);
  CLI::App app{"Benchmarks of the asynchronous integrator (Markdown tables on stdout)"};
  std::string study = "all";
  int cells = 40, ratioCells = 20, ratio = 8, steps = 20, maxNaiveRatio = 64;
  double hL = 5e-3;
  std::vector<std::string> scenes;
  std::string only;
  bool corotational = false, collectFirst = false, rebuildSchur = false, unturned = false;
  int laggedIterations = 0;
  app.add_option("--study", study, "growth | ratio | schur | corotational | contact | steady | setup | modes | all")
      ->check(
          CLI::IsMember({"growth", "ratio", "schur", "corotational", "contact", "steady", "setup", "modes", "all"}));
  app.add_option("--scenes", scenes, "steady and setup studies: scene files, or dragon:SPACING:SET:M:HL");
  app.add_option("--only", only, "steady study: time one configuration only (for callgrind)")
      ->check(CLI::IsMember({"async", "single", "single-hs"}));
  app.add_flag("--corotational", corotational, "steady study: corotational forces");
  app.add_flag("--rebuild-schur", rebuildSchur,
               "steady study: AsyncOptions::KeptFactors::laggedSchur off, Z and H^{LL*} rebuilt every large step "
               "(nonlinear forces)");
  app.add_option("--lagged-iterations", laggedIterations,
                 "steady study: AsyncOptions::KeptFactors::laggedSchurIterations (0: the default)")
      ->check(CLI::Range(0, 100000));
  app.add_flag(
      "--unturned-lagged-factor", unturned,
      "steady study: AsyncOptions::KeptFactors::laggedSchurRotation off (the lagged factor not turned with the body)");
  app.add_flag("--first", collectFirst, "with --only: collect the first step (set-up included) instead");
  app.add_option("--cells", cells, "cells along the bar for the growth and schur studies")->check(CLI::Range(2, 400));
  app.add_option("--ratio-cells", ratioCells, "cells along the bar for the ratio study")->check(CLI::Range(2, 400));
  app.add_option("--m", ratio, "substeps per large step (growth, schur)")->check(CLI::Range(1, 1000));
  app.add_option("--steps", steps, "timed steps per configuration")->check(CLI::Range(3, 100000));
  app.add_option("--max-naive-m", maxNaiveRatio, "largest m for the naive solver")->check(CLI::Range(1, 1000));
  app.add_option("--dt", hL, "large timestep hL")->check(CLI::PositiveNumber);
  CLI11_PARSE(app, argc, argv);
  try {
    std::printf(
        "Machine: %s, %u hardware threads. Command: benchmarkAsync --study %s --cells %d --ratio-cells %d "
        "--m %d --steps %d --dt %g\n\n",
        cpuModel().c_str(), std::thread::hardware_concurrency(), study.c_str(), cells, ratioCells, ratio, steps, hL);
    if (study == "growth" || study == "all") growthStudy(cells, ratio, hL, steps);
    if (study == "ratio" || study == "all") ratioStudy(ratioCells, hL, steps, maxNaiveRatio);
    if (study == "schur" || study == "all") schurStudy(cells, ratio, hL, steps);
    if (study == "corotational" || study == "all") corotationalStudy(ratioCells, ratio, 1.0 / 120.0);
    if (study == "contact" || study == "all") contactStudy(ratioCells, ratio, 1.0 / 120.0);
    if (study == "steady")
      steadyStudy(scenes, steps, corotational, only, collectFirst, rebuildSchur, laggedIterations, unturned);
    if (study == "setup") setUpStudy(scenes, steps);
    if (study == "modes") zModesStudy(scenes, 3, steps, corotational);
  } catch (const asyncfem::Error& e) {
    std::fprintf(stderr, "benchmarkAsync: %s\n", e.what());
    return 1;
  }
  return 0;
}
