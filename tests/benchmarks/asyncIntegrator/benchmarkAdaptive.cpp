// SPDX-License-Identifier: BSD-3-Clause
// Run-time (adaptive) regions on a bouncing scene, printed as a Markdown table: single-rate
// backward Euler over a ladder of steps, async with a fixed region and async with the
// contact region the scene asks for, each against a converged reference (single-rate at a
// fine step everywhere). Every ratio compares runs of the same process.
//
//   benchmarkAdaptive [--scene models/ball/ball.json] [--frames 90] [--repeats 1]
//                     [--reference-steps 64] [--ladder 1,2,4,8,16] [--csv com.csv]
//                     [--contact-stiffness K] [--implicit-contact]
//                     [--track-set NAME] [--track-axis x|y|z] [--fixed-set NAME]
//                     [--motion-verdict]
//
// --contact-stiffness replaces the scene's contact.stiffness; --implicit-contact runs every
// row with contact.implicit (backward Euler solves the step with the contact at its end
// state; async with it at every fast substep's state and L's end state).
// --track-set and --track-axis measure the centre of one vertex set along one axis instead
// of the whole body's height (a part that strikes an obstacle sideways, e.g. a rod tip);
// --fixed-set makes the fixed-region row that vertex set at the contact ratio instead of
// the lower cap; --motion-verdict judges equal cost and equal error on the motion error
// over all frames (with the penetration) instead of the one rebound apex, which frames
// sample coarsely where the part swings faster than the frame rate.
//
// The frames are sampled at the scene's large step (one step per frame), so penetration
// and rebound are seen at every large step. Figures per run:
//   ms/frame  median wall time per frame (frames 1.., re-partitions included)
//   rebound   highest centre of mass (mass-weighted; of the tracked set along the tracked
//             axis when asked for) between the first and second contact,
//             and its error against the reference's ("-" when the reference never leaves
//             the obstacles, or with --motion-verdict: then the verdicts use the COM error)
//   pen.      deepest penetration into any obstacle (planes, spheres) over the run, and its error
//   COM err   relative L2 error of the centre-of-mass height (or the tracked centre) over
//             all frames
#include <CLI/CLI.hpp>
#include <algorithm>
#include <asyncfem/benchmarkTools/benchmarkRun.hpp>
#include <asyncfem/contact/penaltyContact.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/threading.hpp>
#include <asyncfem/integrator/multirateIntegrator.hpp>
#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/sceneIO/simulation.hpp>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

namespace {

using namespace asyncfem;

/// What the rebound and the COM error follow: the mass-weighted centre of some vertices
/// (all by default) along one axis (y by default): its height by default, else its
/// displacement from rest (a relative error of a position far from the origin would say
/// little).
struct Tracking {
  std::vector<int> vertices;
  int axis = 1;
  bool displacement = false;
  std::string name = "COM height";
};

struct Measures {
  std::vector<double> comHeight;  // per frame: the tracked centre
  double rebound = 0.0;           // highest COM between the first two contacts
  double penetration = 0.0;       // deepest vertex inside an obstacle
};

/// Per frame, the COM height and the deepest penetration into the scene's obstacles (the
/// contact model's own measure, PenaltyContact::maxPenetration).
Measures measure(const Trajectory& frames, const TetMesh& mesh, const Eigen::VectorXd& vertexMass,
                 const PenaltyContact& obstacles, const Tracking& tracking) {
  Measures out;
  double totalMass = 0.0;
  for (int v : tracking.vertices) totalMass += vertexMass[v];
  const int a = tracking.axis;
  std::vector<char> inContact;
  for (const Eigen::VectorXd& u : frames) {
    double com = 0.0;
    for (int v : tracking.vertices)
      com += vertexMass[v] * ((tracking.displacement ? 0.0 : mesh.restPosition(v)[a]) + u[(3 * v) + a]);
    const double deepest = obstacles.maxPenetration(u);
    out.comHeight.push_back(com / totalMass);
    out.penetration = std::max(out.penetration, deepest);
    inContact.push_back(deepest > 0.0 ? 1 : 0);
  }
  // The rebound: after the first contact ends, the highest COM until the next contact.
  std::size_t k = 0;
  while (k < inContact.size() && !inContact[k]) ++k;
  while (k < inContact.size() && inContact[k]) ++k;
  for (; k < inContact.size() && !inContact[k]; ++k) out.rebound = std::max(out.rebound, out.comHeight[k]);
  return out;
}

double relativeL2(const std::vector<double>& a, const std::vector<double>& reference) {
  double diff = 0.0, norm = 0.0;
  const std::size_t n = std::min(a.size(), reference.size());
  for (std::size_t k = 0; k < n; ++k) {
    diff += (a[k] - reference[k]) * (a[k] - reference[k]);
    norm += reference[k] * reference[k];
  }
  return norm > 0.0 ? std::sqrt(diff / norm) : 0.0;
}

struct Row {
  BenchmarkRun run;
  Measures measures;
  double reboundError = 0.0, penetrationError = 0.0, comError = 0.0;
};

/// The COM height of every run per frame as CSV (series,role,time,value), for
/// scripts/plot-adaptive.py. Roles: reference, single-rate (the first rung, at hL),
/// equal-cost (the single-rate run of the equal-cost verdict), adaptive, fixed, other.
void writeSeries(const std::string& path, const std::vector<Row>& rows, double hL, const Row* equalCost) {
  std::ofstream out(path);
  if (!out) throw Error("benchmarkAdaptive: cannot write " + path);
  out << "series,role,time,value\n";
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const Row& row = rows[i];
    const char* role = i == 0                 ? "reference"
                       : i == 1               ? "single-rate"
                       : &row == equalCost    ? "equal-cost"
                       : i + 2 == rows.size() ? "adaptive"
                       : i + 1 == rows.size() ? "fixed"
                                              : "other";
    for (std::size_t k = 0; k < row.measures.comHeight.size(); ++k) {
      out << '"' << row.run.configuration.label << "\"," << role << ',' << (static_cast<double>(k + 1) * hL) << ','
          << row.measures.comHeight[k] << '\n';
    }
  }
  if (!out) throw Error("benchmarkAdaptive: writing " + path + " failed");
}

}  // namespace

int main(int argc, char** argv) {
  asyncfem::preferPassiveThreadWaiting(argv);
  CLI::App app{"Run-time (adaptive) async regions on a bouncing scene against single-rate backward Euler"};
  std::string scenePath = "models/ball/ball.json";
  int frames = 90, repeats = 1, referenceSteps = 64;
  std::vector<int> ladder{1, 2, 4, 8, 16};
  app.add_option("--scene", scenePath, "Scene with a contact section and adaptive async regions");
  app.add_option("--frames", frames, "Large steps to run (one per frame)")->check(CLI::PositiveNumber);
  app.add_option("--repeats", repeats, "Timed repeats per configuration")->check(CLI::PositiveNumber);
  app.add_option("--reference-steps", referenceSteps, "Reference: single-rate steps per large step");
  app.add_option("--ladder", ladder, "Single-rate steps per large step to compare")->delimiter(',');
  std::string csvPath;
  app.add_option("--csv", csvPath, "Also write every run's COM height per frame here (for scripts/plot-adaptive.py)");
  double contactStiffness = 0.0;
  app.add_option("--contact-stiffness", contactStiffness, "Replace the scene's contact.stiffness")
      ->check(CLI::PositiveNumber);
  bool implicitContact = false;
  app.add_flag("--implicit-contact", implicitContact, "Every row with contact.implicit (frictionless scenes)");
  std::string trackSet, fixedSet;
  char trackAxis = 'y';
  app.add_option("--track-set", trackSet, "Measure this vertex set's centre instead of the whole body's");
  app.add_option("--track-axis", trackAxis, "Measure along this axis (x, y or z; default y)")
      ->check(CLI::IsMember({'x', 'y', 'z'}));
  app.add_option("--fixed-set", fixedSet, "The fixed-region row: this vertex set at the contact ratio");
  bool motionVerdict = false;
  app.add_flag("--motion-verdict", motionVerdict,
               "Equal-cost and equal-error verdicts on the motion error (all frames) instead of the rebound");
  CLI11_PARSE(app, argc, argv);
  try {
    Scene scene = loadScene(scenePath);
    if (contactStiffness > 0.0) scene.contact.parameters.stiffness = contactStiffness;
    const double hL = requireFrameTiming(scene).timestep;
    // One frame per large step.
    overrideFrameTiming(scene, {.frameCount = frames, .frameRate = 1.0 / hL});
    // contact.implicit for every row when asked for (the single-rate rows' scene is kept
    // apart: the same frames, other integrator options).
    scene.contact.implicit = implicitContact || scene.contact.implicit;
    Scene singleRateScene = scene;
    const std::string singleRateLabel = singleRateScene.contact.implicit ? ", implicit contact" : "";
    const Simulation baseline = buildSimulation(scene);
    const TetMesh& mesh = *baseline.mesh;
    const Eigen::VectorXd lumped = baseline.problem->massMatrix() * Eigen::VectorXd::Ones(mesh.numDofs());
    Eigen::VectorXd vertexMass(mesh.numVertices());
    for (int v = 0; v < mesh.numVertices(); ++v) vertexMass[v] = lumped[3 * v + 1];
    const PenaltyContact obstacles(mesh.restPositions(), scene.contact.planes, scene.contact.spheres,
                                   scene.contact.parameters);
    Tracking tracking;
    tracking.axis = trackAxis - 'x';
    tracking.displacement = !trackSet.empty() || tracking.axis != 1;
    if (trackSet.empty()) {
      for (int v = 0; v < mesh.numVertices(); ++v) tracking.vertices.push_back(v);
      if (tracking.axis != 1) tracking.name = std::string("COM ") + trackAxis + " displacement";
    } else {
      tracking.vertices = mesh.vertexSet(trackSet);  // names the set and the mesh when absent
      tracking.name = trackSet + " " + trackAxis + " displacement";
    }

    std::vector<BenchmarkConfiguration> configurations;
    configurations.push_back({"reference: backward Euler, hL/" + std::to_string(referenceSteps) + singleRateLabel,
                              "backward-euler", referenceSteps});
    for (int steps : ladder) {
      configurations.push_back(
          {"backward Euler, hL/" + std::to_string(steps) + singleRateLabel, "backward-euler", steps});
    }
    nlohmann::json adaptiveOptions = scene.integrator.options;
    const nlohmann::json contact = adaptiveOptions["regions"]["adaptive"]["contact"];
    const int ratio = contact.value("ratio", 8);
    configurations.push_back({"async, adaptive contact region (as shipped)", "async", 1, 0.0, adaptiveOptions});
    // The fixed region a user would draw without run-time regions: the lower cap that the
    // adaptive runs ever made fast (every vertex below the highest vertex the contact
    // region held) and the scene's scheduled regions: joined into the cap when they have
    // its ratio, else kept as they are. A contact region merged into a scheduled one takes
    // the scheduled name, so its vertices count as scheduled here (joined all the same).
    nlohmann::json fixedOptions = adaptiveOptions;
    double capHeight = 0.0;
    int capVertices = 0;
    bool joinsSchedule = false;
    std::vector<char> scheduled(mesh.numVertices(), 0);
    {
      Simulation probe = buildSimulation(configuredScene(scene, configurations.back(), frames));
      for (int k = 0; k < frames; ++k) {
        advanceFrame(probe, k);
        const MultirateIntegrator* multirate = probe.integrator->multirate();
        if (!multirate) continue;
        const std::vector<RegionSummary> regions = multirate->regionSummaries();
        for (int v = 0; v < mesh.numVertices(); ++v) {
          const int region = multirate->regionOfVertex(v);
          if (region < 0) continue;
          if (regions[region].name == "contact") {
            capHeight = std::max(capHeight, mesh.restPosition(v).y());
          } else {
            scheduled[v] = 1;
          }
        }
      }
    }
    // Scheduled regions of the contact ratio join the cap (one region: two that touch
    // would need the nested integrator, which has no substepStatePrediction); others stay apart.
    nlohmann::json schedule = adaptiveOptions["regions"]["adaptive"].value("schedule", nlohmann::json::array());
    const bool joinSchedule = std::all_of(schedule.begin(), schedule.end(),
                                          [&](const nlohmann::json& r) { return r.value("ratio", 0) == ratio; });
    nlohmann::json cap = nlohmann::json::array();
    std::vector<char> inFixedSet(mesh.numVertices(), 0);
    if (!fixedSet.empty())
      for (int v : mesh.vertexSet(fixedSet)) inFixedSet[v] = 1;
    for (int v = 0; v < mesh.numVertices(); ++v) {
      const bool own = fixedSet.empty() ? mesh.restPosition(v).y() <= capHeight : inFixedSet[v] != 0;
      if ((scheduled[v] && joinSchedule) || (!scheduled[v] && own)) cap.push_back(v);
    }
    fixedOptions["regions"] = joinSchedule ? nlohmann::json::array() : schedule;
    for (nlohmann::json& region : fixedOptions["regions"]) {
      region.erase("start");
      region.erase("end");
    }
    fixedOptions["regions"].push_back({{"name", "cap"}, {"ratio", ratio}, {"vertices", cap}});
    capVertices = static_cast<int>(cap.size());
    joinsSchedule = joinSchedule && !schedule.empty();
    configurations.push_back({fixedSet.empty() ? "async, fixed lower cap" : "async, fixed region " + fixedSet, "async",
                              1, 0.0, fixedOptions});

    std::vector<Row> rows;
    for (const BenchmarkConfiguration& configuration : configurations) {
      Row row;
      row.run = runConfiguration(configuration.integrator == "backward-euler" ? singleRateScene : scene, configuration,
                                 frames, repeats);
      row.measures = measure(row.run.frames, mesh, vertexMass, obstacles, tracking);
      rows.push_back(std::move(row));
      std::fprintf(stderr, "ran %s\n", configuration.label.c_str());
    }
    const Measures& reference = rows.front().measures;
    // A scene whose reference never leaves the obstacles again (a body that lands and
    // stays) has no rebound: its error is not defined, and the COM error stands in for it.
    const bool hasRebound = reference.rebound > 0.0;
    const bool byRebound = hasRebound && !motionVerdict;
    for (Row& row : rows) {
      row.reboundError = hasRebound ? std::abs(row.measures.rebound - reference.rebound) / reference.rebound
                                    : std::numeric_limits<double>::quiet_NaN();
      row.penetrationError =
          std::abs(row.measures.penetration - reference.penetration) / std::max(1e-12, reference.penetration);
      row.comError = relativeL2(row.measures.comHeight, reference.comHeight);
    }
    const double singleRateHL = rows[1].run.medianSecondsPerFrame;
    char fixedWhat[96];
    if (fixedSet.empty()) {
      std::snprintf(fixedWhat, sizeof(fixedWhat), "fixed cap below y = %.3f", capHeight);
    } else {
      std::snprintf(fixedWhat, sizeof(fixedWhat), "fixed region %s", fixedSet.c_str());
    }
    std::printf(
        "scene %s, %d large steps of hL = %s, %d vertices, contact region ratio %d, %s (%d vertices%s); "
        "rebound and motion error: %s\n\n",
        scenePath.c_str(), frames, formatTimestep(hL).c_str(), mesh.numVertices(), ratio, fixedWhat, capVertices,
        capVertices > 0 && joinsSchedule ? ", the scheduled regions included" : "", tracking.name.c_str());
    std::printf(
        "| configuration | ms / large step | x single-rate hL | completed | rebound apex (m) | rebound error | max "
        "penetration (m) | penetration error | %s error |\n|---|---|---|---|---|---|---|---|---|\n",
        tracking.name.c_str());
    for (const Row& row : rows) {
      char rebound[64] = "-";
      if (hasRebound) std::snprintf(rebound, sizeof(rebound), "%.3f", row.reboundError);
      std::printf("| %s | %.3f | %.2f | %s | %.4f | %s | %.4f | %.3f | %.2e |\n", row.run.configuration.label.c_str(),
                  1000.0 * row.run.medianSecondsPerFrame, row.run.medianSecondsPerFrame / singleRateHL,
                  row.run.completed ? "yes" : ("no: " + row.run.failure).c_str(), row.measures.rebound, rebound,
                  row.measures.penetration, row.penetrationError, row.comError);
    }
    // Equal cost: the single-rate run closest in time at or below the adaptive run's;
    // equal error: the cheapest single-rate run at or below the adaptive run's error.
    const Row& adaptive = rows[rows.size() - 2];
    const Row* equalCost = nullptr;
    const Row* equalError = nullptr;
    for (std::size_t i = 1; i < rows.size() - 2; ++i) {
      const Row& r = rows[i];
      if (r.run.medianSecondsPerFrame <= adaptive.run.medianSecondsPerFrame) equalCost = &r;
      const bool motion = byRebound ? r.reboundError <= adaptive.reboundError : r.comError <= adaptive.comError;
      if (!equalError && r.run.completed && motion && r.penetrationError <= adaptive.penetrationError) equalError = &r;
    }
    if (!csvPath.empty()) writeSeries(csvPath, rows, hL, equalCost);
    std::printf("\n");
    const char* motionName = byRebound ? "rebound" : tracking.name.c_str();
    const auto motionError = [&](const Row& r) { return byRebound ? r.reboundError : r.comError; };
    if (equalCost) {
      std::printf(
          "equal cost: %s (%.2fx the adaptive run's time) has %s error %.3g and penetration error %.3f "
          "against the adaptive run's %.3g and %.3f\n",
          equalCost->run.configuration.label.c_str(),
          equalCost->run.medianSecondsPerFrame / adaptive.run.medianSecondsPerFrame, motionName,
          motionError(*equalCost), equalCost->penetrationError, motionError(adaptive), adaptive.penetrationError);
    } else {
      std::printf("equal cost: every single-rate run of the ladder costs more than the adaptive run\n");
    }
    if (equalError) {
      std::printf("equal error: %s reaches the adaptive run's %s and penetration errors at %.2fx its time\n",
                  equalError->run.configuration.label.c_str(), motionName,
                  equalError->run.medianSecondsPerFrame / adaptive.run.medianSecondsPerFrame);
    } else {
      std::printf("equal error: no single-rate run of the ladder reaches the adaptive run's errors\n");
    }
  } catch (const Error& e) {
    std::fprintf(stderr, "benchmarkAdaptive: %s\n", e.what());
    return 1;
  }
  return 0;
}
