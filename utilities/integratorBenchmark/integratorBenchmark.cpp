// SPDX-License-Identifier: BSD-3-Clause
// integratorBenchmark: run time against error for integrator configurations on a scene.
//
//   integratorBenchmark SCENE.json [--configs FILE.json] [--config SPEC]... [--frames N]
//                       [--repeats R] [--out DIR] [--reference auto|modal|trapezoidal]
//                       [--max-modal-dofs N] [--vertex V] [--quick]
//   integratorBenchmark --table [--models DIR] [--table-frames N] [--repeats R] [--out DIR]
//
// For every configuration: wall time per frame (median over repeats, frame 0 excluded),
// factorizations, back-substitutions and their flops per frame, and the relative L2 error
// of the displacement over the frames against a reference (exact modal solution for
// linear scenes, else a fine trapezoidal run), per vertex group (each fast region, L,
// all). Then the equal-cost and equal-error single-rate answers for every multirate
// configuration, CSV files and PNG plots. docs/benchmarks.md describes the output.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <asyncfem/benchmarkTools/costInterpolation.hpp>
#include <asyncfem/benchmarkTools/errorMetrics.hpp>
#include <asyncfem/benchmarkTools/modalReference.hpp>
#include <asyncfem/benchmarkTools/plot.hpp>
#include <asyncfem/benchmarkTools/sceneReference.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/core/threading.hpp>
#include <asyncfem/image/png.hpp>
#include <asyncfem/modalAnalysis/lowestModes.hpp>
#include <asyncfem/modalAnalysis/regionModes.hpp>
#include <asyncfem/sceneIO/asyncScene.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <sstream>

#include "benchmarkRun.hpp"
#include "commandLine.hpp"
#include "performanceTable.hpp"

namespace {

namespace fs = std::filesystem;
using namespace asyncfem;
using namespace asyncfem::bench;

struct CommandLine {
  std::string scene;
  std::string configsFile;
  std::vector<std::string> configSpecs;
  std::optional<int> frames;
  int repeats = 3;
  std::string out = "benchmark-out";
  std::string reference = "auto";
  int maxModalDofs = 5000;
  std::optional<int> vertex;
  std::vector<double> keptWindow;
  int modes = 0;  ///< > 0: print the modal table of the scene's regions first  ///< [t0, t1] for the motion-kept table;
                  ///< empty: after the last load window
  bool quick = false;
  bool table = false;
  std::string models = "models";
  int tableFrames = 20;
};

std::string formatDouble(double value, int precision = 4) {
  std::ostringstream out;
  out.precision(precision);
  out << value;
  return out.str();
}

struct Reference {
  std::string description;
  Trajectory frames;
  std::shared_ptr<const ModalReference> modal;  ///< set when the reference is the exact modal solution
};

// The exact modal solution when the scene allows it, else a trapezoidal run at a step far
// below every configuration's smallest step (design note, "What accurate means here").
Reference computeReference(const Scene& scene, const Simulation& baseline, const std::vector<Configuration>& configs,
                           int frames, const CommandLine& options) {
  const std::string reason = modalReferenceUnsupportedReason(scene, baseline, options.maxModalDofs);
  Reference reference;
  if (options.reference == "modal" && !reason.empty()) {
    throw Error("--reference modal: not available for this scene: " + reason);
  }
  if (options.reference != "trapezoidal" && reason.empty()) {
    Stopwatch watch;
    const DynamicSystem& system = baseline.integrator->system();
    Eigen::SparseMatrix<double> stiffness = system.forceModel->createStiffnessMatrix();
    system.forceModel->tangentStiffness(Eigen::VectorXd::Zero(system.numDofs()), stiffness);
    auto modal = std::make_shared<const ModalReference>(system.mass, stiffness, system.freeDofs, system.rayleighMass,
                                                        system.rayleighStiffness);
    reference.frames = modal->displacements(sceneLoad(scene, baseline), frameTimes(scene, frames));
    reference.modal = modal;
    reference.description = "exact modal solution (" + std::to_string(modal->numFree()) + " modes, " +
                            formatDouble(watch.stop(), 3) + " s)";
    return reference;
  }
  // Smallest step of any configuration (substeps included), divided by 4.
  double smallest = 1.0 / scene.frames.rate;
  for (const Configuration& c : configs) {
    const Scene configured = configuredScene(scene, c, frames);
    double h = configured.integrator.timestep;
    if (isMultirate(c.integrator) && c.options.contains("regions") && c.options["regions"].is_array()) {
      int maxRatio = 1;
      for (const nlohmann::json& region : c.options["regions"]) maxRatio = std::max(maxRatio, region.value("ratio", 1));
      h /= maxRatio;
    }
    smallest = std::min(smallest, h);
  }
  const int stepsPerFrame = static_cast<int>(std::ceil((1.0 / scene.frames.rate) / (smallest / 4.0)));
  Configuration fine;
  fine.integrator = "trapezoidal";
  fine.stepsPerFrame = stepsPerFrame;
  Stopwatch watch;
  const RunResult run = runConfiguration(scene, fine, frames, 1);
  if (!run.completed) throw Error("the trapezoidal reference run failed: " + run.failure);
  reference.frames = run.frames;
  reference.description = "trapezoidal run at h = " + formatTimestep(run.timestep) + " (" +
                          (reason.empty() ? std::string("requested") : "no modal reference: " + reason) + ", " +
                          formatDouble(watch.stop(), 3) + " s)";
  return reference;
}

// Vertex groups for the errors: each fast region of the first multirate configuration, L
// (every other vertex) and all vertices.
std::vector<VertexGroup> errorGroups(const Scene& scene, const Simulation& baseline,
                                     const std::vector<Configuration>& configs) {
  std::vector<VertexGroup> groups;
  const TetMesh& mesh = *baseline.mesh;
  for (const Configuration& c : configs) {
    if (!isMultirate(c.integrator)) continue;
    const Scene configured = configuredScene(scene, c, 1);
    const AsyncSettings parsed = parseAsyncOptions(configured, mesh, baseline.integrator->system().freeDofs, c.options);
    std::vector<bool> fast(static_cast<std::size_t>(mesh.numVertices()), false);
    for (const AsyncRegion& region : parsed.regions) {
      groups.push_back({region.name.empty() ? "S" + std::to_string(groups.size()) : region.name, region.vertices});
      for (const int v : region.vertices) fast[static_cast<std::size_t>(v)] = true;
    }
    VertexGroup large{"L", {}};
    for (int v = 0; v < mesh.numVertices(); ++v) {
      if (!fast[static_cast<std::size_t>(v)]) large.vertices.push_back(v);
    }
    if (!large.vertices.empty()) groups.push_back(large);
    break;
  }
  groups.push_back({"all", {}});
  return groups;
}

std::string family(const Configuration& c) {
  std::string name = c.integrator;
  for (const char* key : {"coupling", "schur", "method"}) {
    if (c.options.contains(key)) name += " " + c.options[key].get<std::string>();
  }
  return name;
}

void writeResultsCsv(const fs::path& path, const std::vector<RunResult>& results,
                     const std::vector<VertexGroup>& groups) {
  std::ofstream out(path);
  out << "label,integrator,timestep,steps_per_frame,ratios,completed,failed_frame,seconds_per_frame_median,"
         "seconds_per_frame_min,repeats,setup_seconds,first_frame_seconds,factorizations_per_frame,solves_per_frame,"
         "factor_flops_per_frame,solve_flops_per_frame,factor_nonzeros";
  for (const VertexGroup& g : groups) out << ",error_" << g.name;
  out << "\n";
  out.precision(8);
  for (const RunResult& r : results) {
    out << '"' << r.configuration.label << "\"," << r.configuration.integrator << ',' << r.timestep << ','
        << r.stepsPerFrame << ",\"" << r.ratios << "\"," << (r.completed ? 1 : 0) << ',' << r.failedFrame << ','
        << r.medianSecondsPerFrame << ',' << r.minSecondsPerFrame << ',' << r.secondsPerFrame.size() << ','
        << r.setupSeconds << ',' << r.firstFrameSeconds << ',' << r.factorizationsPerFrame << ',' << r.solvesPerFrame
        << ',' << r.factorFlopsPerFrame << ',' << r.solveFlopsPerFrame << ',' << r.factorNonZeros;
    for (const VertexGroup& g : groups) {
      const auto it = r.errors.find(g.name);
      out << ',' << (it == r.errors.end() ? std::nan("") : it->second);
    }
    out << "\n";
  }
}

// Motion kept per frequency band (phase-insensitive; what the paper calls retained
// motion), against the exact modal solution. Bands in omega hL of the scene's own step:
// [0, 0.3) and [0.3, 1) are resolved by hL, [1, m) only by the small step hL / m (m: the
// largest ratio of any configuration), [m, inf) by neither.
void writeMotionKept(const fs::path& path, const Scene& scene, const std::vector<RunResult>& results,
                     const ModalReference& modal, const Reference& reference) {
  const double hL = scene.integrator.timestep;
  int maxRatio = 1;
  for (const RunResult& r : results) {
    std::stringstream ratios(r.ratios);
    std::string item;
    while (std::getline(ratios, item, ',')) {
      if (!item.empty()) maxRatio = std::max(maxRatio, std::stoi(item));
    }
  }
  if (maxRatio < 2) maxRatio = 8;
  const std::vector<double> edges{0.0, 0.3 / hL, 1.0 / hL, maxRatio / hL};
  const std::vector<std::string> names{"omega hL < 0.3", "0.3 to 1", "1 to " + std::to_string(maxRatio),
                                       ">= " + std::to_string(maxRatio)};
  std::ofstream csv(path);
  csv << "label";
  for (std::size_t b = 0; b < edges.size(); ++b) csv << ",kept_band" << b;
  csv << "\n";
  csv.precision(8);
  std::cout << "\n## Motion kept per frequency band\n\nRMS over frames of the modal coordinates of each band, run / "
               "exact (1: nothing lost; below 1: artificial damping; insensitive to phase). Bands by omega hL, hL = "
            << formatTimestep(hL) << " (the scene's step).\n\n| configuration |";
  // The reference is projected onto the modes once and compared with every run.
  const std::vector<Eigen::VectorXd> referenceModal = modalTrajectory(modal, reference.frames);
  const std::vector<ModalBand> header = motionKeptPerBand(modal.eigenvalues(), referenceModal, referenceModal, edges);
  for (std::size_t b = 0; b < header.size(); ++b)
    std::cout << " " << names[b] << " (" << header[b].modes << " modes) |";
  std::cout << "\n|---|";
  for (std::size_t b = 0; b < header.size(); ++b) std::cout << "---|";
  std::cout << "\n";
  for (const RunResult& r : results) {
    const std::vector<ModalBand> bands =
        motionKeptPerBand(modal.eigenvalues(), modalTrajectory(modal, r.frames), referenceModal, edges);
    std::cout << "| " << r.configuration.label << " |";
    csv << '"' << r.configuration.label << '"';
    for (const ModalBand& band : bands) {
      std::cout << " " << (std::isnan(band.kept) ? std::string("-") : formatDouble(band.kept, 3)) << " |";
      csv << ',' << band.kept;
    }
    std::cout << "\n";
    csv << "\n";
  }
}

struct EqualAnswers {
  const RunResult* run = nullptr;
  std::string group;
  std::string costKind;  // "time" or "flops"
  EqualCostAnswer atEqualCost;
  EqualErrorAnswer atEqualError;
  std::string problem;  // non-empty: could not answer
};

std::vector<EqualAnswers> equalAnswers(const std::vector<RunResult>& results,
                                       const std::vector<std::string>& groupNames) {
  std::vector<EqualAnswers> answers;
  for (const std::string& group : groupNames) {
    for (const std::string& costKind : {std::string("time"), std::string("flops")}) {
      std::vector<SingleRatePoint> points;
      for (const RunResult& r : results) {
        if (r.configuration.integrator != "backward-euler" || !r.completed) continue;
        const double cost = costKind == "time" ? r.medianSecondsPerFrame : r.flopsPerFrame();
        const auto it = r.errors.find(group);
        if (it == r.errors.end() || !(cost > 0.0) || !(it->second > 0.0)) continue;
        points.push_back({r.timestep, cost, it->second});
      }
      for (const RunResult& r : results) {
        if (!isMultirate(r.configuration.integrator) || !r.completed) continue;
        EqualAnswers answer;
        answer.run = &r;
        answer.group = group;
        answer.costKind = costKind;
        const double cost = costKind == "time" ? r.medianSecondsPerFrame : r.flopsPerFrame();
        const auto it = r.errors.find(group);
        try {
          if (points.size() < 2) throw Error("fewer than two measured single-rate backward Euler points");
          if (it == r.errors.end()) throw Error("no error for group " + group);
          answer.atEqualCost = singleRateAtEqualCost(points, cost);
          answer.atEqualError = singleRateAtEqualError(points, it->second);
        } catch (const Error& error) {
          answer.problem = error.what();
        }
        answers.push_back(answer);
      }
    }
  }
  return answers;
}

void plotPareto(const fs::path& path, const std::vector<RunResult>& results, const std::string& group,
                const std::string& sceneName) {
  PlotSpec spec;
  spec.title = "Error vs time per frame: " + sceneName + " (" + group + ")";
  spec.xLabel = "wall time per frame (s, median)";
  spec.yLabel = "relative L2 error of u over the frames (" + group + ")";
  spec.logX = spec.logY = true;
  std::map<std::string, std::size_t> seriesOf;
  for (const RunResult& r : results) {
    const auto it = r.errors.find(group);
    if (!r.completed || it == r.errors.end()) continue;
    const std::string name = family(r.configuration);
    if (!seriesOf.count(name)) {
      seriesOf[name] = spec.series.size();
      const int index = static_cast<int>(spec.series.size());
      spec.series.push_back({name, {}, {}, paletteColor(index), paletteMarker(index), name == "backward-euler"});
    }
    PlotSeries& s = spec.series[seriesOf[name]];
    s.x.push_back(r.medianSecondsPerFrame);
    s.y.push_back(it->second);
  }
  // Points keep the configuration order (backward Euler: increasing steps per frame), so
  // the connected single-rate curve follows the timestep even where timing noise reorders it.
  writePng(path, renderPlot(spec, 1100, 650), PngCompression::standard);
}

void plotVertex(const fs::path& path, const std::vector<RunResult>& results, const Reference& reference,
                const Scene& scene, int vertex, const std::string& sceneName) {
  PlotSpec spec;
  spec.title = "Displacement of vertex " + std::to_string(vertex) + ": " + sceneName;
  spec.xLabel = "time (s)";
  spec.yLabel = "|u| of vertex " + std::to_string(vertex);
  const std::vector<double> times = frameTimes(scene, static_cast<int>(reference.frames.size()));
  spec.series.push_back(
      {"reference", times, vertexDisplacementNorms(reference.frames, vertex), {0, 0, 0}, Marker::none, true});
  int index = 0;
  for (const RunResult& r : results) {
    if (!r.configuration.plotTrajectory || r.frames.empty()) continue;
    const std::vector<double> t = frameTimes(scene, static_cast<int>(r.frames.size()));
    spec.series.push_back(
        {r.configuration.label, t, vertexDisplacementNorms(r.frames, vertex), paletteColor(index), Marker::none, true});
    ++index;
  }
  writePng(path, renderPlot(spec, 1100, 650), PngCompression::standard);
}

/// How much of one vertex's free vibration a run keeps after the last load window closes:
/// RMS over those frames of |u_v - c| divided by the reference's, c the reference's mean
/// position of the vertex over the same frames (the equilibrium it oscillates about). 1 keeps
/// all of the motion; phase is ignored (what the paper's Figures 4 and 7 show).
double motionKeptAfterRelease(const Trajectory& run, const Trajectory& reference, const std::vector<double>& times,
                              double release, double until, int vertex) {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  int count = 0;
  for (std::size_t k = 0; k < reference.size() && k < times.size(); ++k) {
    if (times[k] <= release || times[k] > until) continue;
    centre += reference[k].segment<3>(3 * vertex);
    ++count;
  }
  if (count == 0) return std::numeric_limits<double>::quiet_NaN();
  centre /= count;
  double runSum = 0.0, referenceSum = 0.0;
  for (std::size_t k = 0; k < reference.size() && k < run.size() && k < times.size(); ++k) {
    if (times[k] <= release || times[k] > until) continue;
    runSum += (run[k].segment<3>(3 * vertex) - centre).squaredNorm();
    referenceSum += (reference[k].segment<3>(3 * vertex) - centre).squaredNorm();
  }
  return referenceSum > 0.0 ? std::sqrt(runSum / referenceSum) : std::numeric_limits<double>::quiet_NaN();
}

/// The table of motion kept at `vertex` after the loads end, for every configuration, and
/// for each multirate one what single-rate backward Euler keeps at the same wall time and
/// at the same flops per frame (log-log interpolation between the measured BE runs).
void printMotionKept(const std::vector<RunResult>& results, const Trajectory& reference, const Scene& scene,
                     const Simulation& baseline, int vertex, const std::vector<double>& window) {
  const PiecewiseConstantLoad load = sceneLoad(scene, baseline);
  double release = load.breakpoints.empty() ? 0.0 : load.breakpoints.back();
  double until = std::numeric_limits<double>::infinity();
  if (window.size() == 2) {
    release = std::max(release, window[0]);
    until = window[1];
  }
  const std::vector<double> times = frameTimes(scene, static_cast<int>(reference.size()));
  std::map<const RunResult*, double> kept;
  std::vector<SingleRatePoint> byTime, byFlops;
  for (const RunResult& r : results) {
    if (!r.completed) continue;
    const double value = motionKeptAfterRelease(r.frames, reference, times, release, until, vertex);
    kept[&r] = value;
    if (r.configuration.integrator == "backward-euler" && value > 0.0) {
      byTime.push_back({r.timestep, r.medianSecondsPerFrame, value});
      byFlops.push_back({r.timestep, r.flopsPerFrame(), value});
    }
  }
  std::cout << "\n## Motion kept at vertex " << vertex << " after the loads end (" << formatDouble(release, 3)
            << " s < t" << (std::isfinite(until) ? " <= " + formatDouble(until, 3) + " s" : "")
            << ")\n\nRMS of the vertex's displacement about its equilibrium, over the frames after the last load "
               "window, divided by the reference's (phase ignored). BE columns: single-rate backward Euler "
               "interpolated to the same wall time / flops per frame (* extrapolated).\n\n"
               "| configuration | time/frame (ms) | kept | BE kept at equal time | ratio | BE kept at equal flops | "
               "ratio |\n|---|---|---|---|---|---|---|\n";
  for (const RunResult& r : results) {
    if (!r.completed) continue;
    const double value = kept[&r];
    std::cout << "| " << r.configuration.label << " | " << formatDouble(1e3 * r.medianSecondsPerFrame, 3) << " | "
              << formatDouble(value, 3) << " |";
    if (!isMultirate(r.configuration.integrator) || byTime.size() < 2) {
      std::cout << " | | | |\n";
      continue;
    }
    for (const auto* points : {&byTime, &byFlops}) {
      const double cost = points == &byTime ? r.medianSecondsPerFrame : r.flopsPerFrame();
      try {
        const EqualCostAnswer answer = singleRateAtEqualCost(*points, cost);
        const std::string mark = answer.extrapolated ? "*" : "";
        std::cout << " " << formatDouble(answer.error, 3) << mark << " | " << formatDouble(value / answer.error, 3)
                  << "x" << mark << " |";
      } catch (const Error& error) {
        std::cout << " n/a | |";
      }
    }
    std::cout << "\n";
  }
}

/// The figure of the paper's Figures 4 and 7 for one vertex: the signed displacement
/// coordinate that moves most in the reference, over time, for the reference, backward
/// Euler at the largest measured step, the backward Euler run whose wall time per frame is
/// nearest the multirate run's ("equal cost"), and the multirate run with the scene's own
/// ratios and no other option (else the first multirate run). Nothing is drawn without a
/// completed multirate run and two backward Euler runs.
void plotVertexAgainstEqualCost(const fs::path& path, const std::vector<RunResult>& results, const Reference& reference,
                                const Scene& scene, int vertex, const std::string& sceneName) {
  std::string sceneRatios;
  if (scene.integrator.options.contains("regions") && scene.integrator.options["regions"].is_array()) {
    for (const nlohmann::json& region : scene.integrator.options["regions"])
      sceneRatios += (sceneRatios.empty() ? "" : ",") + std::to_string(region.value("ratio", 1));
  }
  const RunResult* multirate = nullptr;
  const RunResult* coarse = nullptr;
  for (const RunResult& r : results) {
    if (!r.completed || r.frames.empty()) continue;
    if (isMultirate(r.configuration.integrator)) {
      const bool plain = !r.configuration.options.contains("coupling") && !r.configuration.options.contains("schur") &&
                         !r.configuration.options.contains("method");
      if (!multirate || (plain && r.ratios == sceneRatios)) multirate = &r;
    } else if (r.configuration.integrator == "backward-euler" && (!coarse || r.timestep > coarse->timestep)) {
      coarse = &r;
    }
  }
  if (!multirate || !coarse) return;
  const RunResult* equalCost = nullptr;
  for (const RunResult& r : results) {
    if (!r.completed || r.frames.empty() || r.configuration.integrator != "backward-euler" || &r == coarse) continue;
    const auto distance = [&](const RunResult& x) {
      return std::abs(std::log(x.medianSecondsPerFrame / multirate->medianSecondsPerFrame));
    };
    if (!equalCost || distance(r) < distance(*equalCost)) equalCost = &r;
  }
  if (!equalCost) return;
  int coordinate = 0;
  Eigen::Vector3d energy = Eigen::Vector3d::Zero();
  for (const Eigen::VectorXd& u : reference.frames) energy += u.segment<3>(3 * vertex).cwiseAbs2();
  energy.maxCoeff(&coordinate);
  const auto component = [&](const Trajectory& frames) {
    std::vector<double> values;
    for (const Eigen::VectorXd& u : frames) values.push_back(u[3 * vertex + coordinate]);
    return values;
  };
  PlotSpec spec;
  const char* axis = coordinate == 0 ? "x" : coordinate == 1 ? "y" : "z";
  spec.title = "Vertex " + std::to_string(vertex) + ", " + axis + " displacement: " + sceneName;
  spec.xLabel = "time (s)";
  spec.yLabel = std::string("u_") + axis + " of vertex " + std::to_string(vertex);
  spec.series.push_back({"exact",
                         frameTimes(scene, static_cast<int>(reference.frames.size())),
                         component(reference.frames),
                         {0, 0, 0},
                         Marker::none,
                         true});
  const std::vector<std::pair<const RunResult*, std::string>> runs{
      {coarse, coarse->configuration.label + " (largest step)"},
      {equalCost, equalCost->configuration.label + " (nearest wall time)"},
      {multirate, multirate->configuration.label}};
  int index = 0;
  for (const auto& [run, label] : runs) {
    spec.series.push_back({label, frameTimes(scene, static_cast<int>(run->frames.size())), component(run->frames),
                           paletteColor(index++), Marker::none, true});
  }
  writePng(path, renderPlot(spec, 1100, 650), PngCompression::standard);
}

/// The K lowest modes of the scene (linear K, the scene's mass) with omega hL, omega hS and
/// the share of each fast region, and the verdict: which modes async can keep here
/// (docs/asynchronous-integrator.md, "Which modes can async keep?").
void printSceneModes(const Scene& scene, const Simulation& baseline, int count) {
  const FreeDofs& freeDofs = baseline.integrator->system().freeDofs;
  std::vector<AsyncRegion> regions;
  const nlohmann::json& options = scene.integrator.options;
  if (isMultirate(scene.integrator.name) && options.is_object() && options.contains("regions") &&
      options["regions"].is_array()) {
    regions = parseAsyncOptions(scene, *baseline.mesh, freeDofs, options).regions;
  }
  const VibrationMatrices matrices = vibrationMatrices(*baseline.mesh, scene.mass);
  ModalOptions modal;
  modal.count = std::min(count, freeDofs.numFree() - 1);
  const ModalResult modes = lowestModes(matrices.stiffness, matrices.mass, freeDofs, modal);
  std::cout << "\n## The " << modal.count << " lowest modes and the scene's fast regions (eigensolve "
            << formatDouble(modes.solveSeconds, 3) << " s)\n\n";
  printRegionModeReport(std::cout, analyseRegionModes(modes, matrices.mass, modalRegions(regions),
                                                      scene.integrator.timestep, scene.frames.rate));
}

// The vertex of the first fast region (else of the whole mesh) with the largest reference
// displacement over the frames.
int chooseVertex(const Reference& reference, const std::vector<VertexGroup>& groups, int numVertices) {
  std::vector<int> candidates = groups.size() > 1 ? groups.front().vertices : std::vector<int>{};
  if (candidates.empty()) {
    for (int v = 0; v < numVertices; ++v) candidates.push_back(v);
  }
  int best = candidates.front();
  double bestNorm = -1.0;
  for (const int v : candidates) {
    double peak = 0.0;
    for (const Eigen::VectorXd& u : reference.frames) peak = std::max(peak, u.segment<3>(3 * v).norm());
    if (peak > bestNorm) {
      bestNorm = peak;
      best = v;
    }
  }
  return best;
}

int runBenchmark(const CommandLine& options) {
  Scene scene = loadScene(options.scene);
  const std::string sceneName = fs::path(options.scene).stem().string();
  int frames = options.frames.value_or(scene.frames.count);
  int repeats = options.repeats;
  if (options.quick) {
    frames = std::min(frames, 30);
    repeats = 1;
  }
  fs::create_directories(options.out);

  // A single-rate build of the scene gives the mesh and matrices.
  Configuration baselineConfig;
  baselineConfig.stepsPerFrame = 1;
  const Simulation baseline = buildSimulation(configuredScene(scene, baselineConfig, 1));

  std::vector<Configuration> configs;
  if (!options.configsFile.empty()) configs = readConfigurations(options.configsFile, scene);
  for (const std::string& spec : options.configSpecs) configs.push_back(parseConfigurationSpec(spec, scene));
  if (configs.empty()) configs = defaultConfigurations(scene, baseline);
  // Every configuration is built once before the reference is computed (the expensive
  // part), so a bad one (unknown integrator or option, a timestep that does not divide
  // the frame interval) fails at once.
  for (const Configuration& c : configs) {
    try {
      (void)buildSimulation(configuredScene(scene, c, 1));
    } catch (const Error& error) {
      throw Error("configuration \"" + c.label + "\": " + error.what());
    }
  }

  std::cout << "# integratorBenchmark: " << options.scene << "\n\n";
  std::cout << "Machine: " << machineDescription() << "\n";
  std::cout << "Mesh: " << baseline.mesh->numVertices() << " vertices, " << baseline.mesh->numElements() << " tets, "
            << baseline.integrator->system().freeDofs.numFree() << " free DOFs; " << frames << " frames at "
            << scene.frames.rate << " per s; " << repeats
            << " repeats (time per frame: median over repeats of the mean over frames 1.., frame 0 is warm-up)\n";
  std::cout.flush();

  const Reference reference = computeReference(scene, baseline, configs, frames, options);
  std::cout << "Reference: " << reference.description << "\n";
  if (options.modes > 0) printSceneModes(scene, baseline, options.modes);
  const std::vector<VertexGroup> groups = errorGroups(scene, baseline, configs);

  std::vector<RunResult> results;
  for (std::size_t k = 0; k < configs.size(); ++k) {
    std::cerr << "integratorBenchmark: [" << (k + 1) << "/" << configs.size() << "] " << configs[k].label << "\n";
    // Long explicit runs (thousands of steps per frame) are timed once.
    const bool longRun =
        configs[k].stepsPerFrame > 0 && static_cast<long long>(configs[k].stepsPerFrame) * frames > 20000;
    RunResult r = runConfiguration(scene, configs[k], frames, longRun ? 1 : repeats);
    for (const VertexGroup& g : groups) r.errors[g.name] = relativeL2Error(r.frames, reference.frames, g);
    results.push_back(std::move(r));
  }

  // Results table.
  std::cout << "\n| configuration | h | m | time/frame (ms) | factor./frame | solves/frame | Mflop/frame |";
  for (const VertexGroup& g : groups) std::cout << " error " << g.name << " |";
  std::cout << "\n|---|---|---|---|---|---|---|";
  for (std::size_t g = 0; g < groups.size(); ++g) std::cout << "---|";
  std::cout << "\n";
  for (const RunResult& r : results) {
    std::cout << "| " << r.configuration.label << " | " << formatTimestep(r.timestep) << " | "
              << (r.ratios.empty() ? "-" : r.ratios) << " | " << formatDouble(1e3 * r.medianSecondsPerFrame, 3) << " | "
              << formatDouble(r.factorizationsPerFrame, 3) << " | " << formatDouble(r.solvesPerFrame, 4) << " | "
              << formatDouble(1e-6 * r.flopsPerFrame(), 4) << " |";
    for (const VertexGroup& g : groups) std::cout << " " << formatDouble(r.errors.at(g.name), 3) << " |";
    std::cout << "\n";
  }
  for (const RunResult& r : results) {
    if (!r.completed) {
      std::cout << "\nUNSTABLE: " << r.configuration.label << " stopped at frame " << r.failedFrame << ": " << r.failure
                << "\n";
    }
  }
  writeResultsCsv(fs::path(options.out) / "results.csv", results, groups);
  if (reference.modal)
    writeMotionKept(fs::path(options.out) / "motion-kept.csv", scene, results, *reference.modal, reference);

  // Equal cost and equal error against single-rate backward Euler.
  std::vector<std::string> answerGroups{"all"};
  if (groups.size() > 1) answerGroups.insert(answerGroups.begin(), groups.front().name);
  const std::vector<EqualAnswers> answers = equalAnswers(results, answerGroups);
  std::cout << "\n## Equal cost and equal error against single-rate backward Euler\n\n"
               "Interpolation: piecewise linear in log-log between the measured backward Euler runs "
               "(cost against h and error against h; extended along the end segment outside the measured "
               "range, marked *). Cost = median wall time per frame, or factor + solve flops per frame.\n\n";
  std::cout << "| configuration | error of | cost | multirate cost | multirate error | BE h at equal cost | BE error "
               "there | BE h at equal error | BE cost there | speed-up at equal error |\n";
  std::cout << "|---|---|---|---|---|---|---|---|---|---|\n";
  std::ofstream equalCsv(fs::path(options.out) / "equal-cost-error.csv");
  equalCsv << "label,group,cost_kind,multirate_cost,multirate_error,equal_cost_timestep,equal_cost_error,"
              "equal_error_timestep,equal_error_cost,speedup_at_equal_error,extrapolated,problem\n";
  equalCsv.precision(8);
  for (const EqualAnswers& a : answers) {
    const RunResult& r = *a.run;
    const double cost = a.costKind == "time" ? r.medianSecondsPerFrame : r.flopsPerFrame();
    const double error = r.errors.at(a.group);
    const std::string unit = a.costKind == "time" ? " ms" : " Mflop";
    const double scale = a.costKind == "time" ? 1e3 : 1e-6;
    if (!a.problem.empty()) {
      std::cout << "| " << r.configuration.label << " | " << a.group << " | " << a.costKind << " | "
                << formatDouble(scale * cost, 3) << unit << " | " << formatDouble(error, 3) << " | n/a: " << a.problem
                << " | | | | |\n";
      equalCsv << '"' << r.configuration.label << "\"," << a.group << ',' << a.costKind << ',' << cost << ',' << error
               << ",,,,,,,\"" << a.problem << "\"\n";
      continue;
    }
    const double speedup = a.atEqualError.cost / cost;
    const std::string costMark = a.atEqualCost.extrapolated ? "*" : "";
    const std::string errorMark = a.atEqualError.extrapolated ? "*" : "";
    std::cout << "| " << r.configuration.label << " | " << a.group << " | " << a.costKind << " | "
              << formatDouble(scale * cost, 3) << unit << " | " << formatDouble(error, 3) << " | "
              << formatDouble(a.atEqualCost.timestep, 3) << costMark << " | " << formatDouble(a.atEqualCost.error, 3)
              << costMark << " | " << formatDouble(a.atEqualError.timestep, 3) << errorMark << " | "
              << formatDouble(scale * a.atEqualError.cost, 3) << unit << errorMark << " | " << formatDouble(speedup, 3)
              << "x" << errorMark << " |\n";
    equalCsv << '"' << r.configuration.label << "\"," << a.group << ',' << a.costKind << ',' << cost << ',' << error
             << ',' << a.atEqualCost.timestep << ',' << a.atEqualCost.error << ',' << a.atEqualError.timestep << ','
             << a.atEqualError.cost << ',' << speedup << ','
             << ((a.atEqualCost.extrapolated || a.atEqualError.extrapolated) ? 1 : 0) << ",\n";
  }

  const int vertex = options.vertex.value_or(chooseVertex(reference, groups, baseline.mesh->numVertices()));
  printMotionKept(results, reference.frames, scene, baseline, vertex, {});
  if (!options.keptWindow.empty())
    printMotionKept(results, reference.frames, scene, baseline, vertex, options.keptWindow);

  // Plots.
  if (pngSupported()) {
    for (const VertexGroup& g : groups) {
      if (g.name != "all" && g.name != groups.front().name) continue;
      const fs::path path = fs::path(options.out) / ("pareto-" + g.name + ".png");
      plotPareto(path, results, g.name, sceneName);
      std::cout << "\nWrote " << path.string();
    }
    const fs::path path = fs::path(options.out) / "vertex-displacement.png";
    plotVertex(path, results, reference, scene, vertex, sceneName);
    std::cout << "\nWrote " << path.string() << " (vertex " << vertex << ")\n";
    const fs::path focus = fs::path(options.out) / "vertex-equal-cost.png";
    fs::remove(focus);  // an older run's figure must not survive a run that draws none
    plotVertexAgainstEqualCost(focus, results, reference, scene, vertex, sceneName);
    if (fs::exists(focus)) std::cout << "Wrote " << focus.string() << "\n";
  } else {
    std::cout << "\nNo plots: this build has no PNG support (libpng was not found when it was configured); CSV only.\n";
  }
  std::cout << "Wrote " << (fs::path(options.out) / "results.csv").string() << " and "
            << (fs::path(options.out) / "equal-cost-error.csv").string() << "\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  asyncfem::preferPassiveThreadWaiting(argv);
  CLI::App app{"Run time against error of integrator configurations on a scene (docs/benchmarks.md)"};
  CommandLine options;
  app.add_option("scene", options.scene, "Scene file (JSON)");
  app.add_option("--configs", options.configsFile, "JSON file {\"configurations\": [...]}");
  app.add_option("--config", options.configSpecs,
                 "NAME[:spf=N|dt=H][:ratio=M][:schur=..][:method=..][:recovery=..][:label=..] (repeatable)");
  app.add_option("--frames", options.frames, "Frames per run (default: the scene's)")->check(asyncfem::cli::atLeast(1));
  app.add_option("--repeats", options.repeats, "Timed repeats per configuration")->check(asyncfem::cli::atLeast(1));
  app.add_option("--out", options.out, "Output folder for CSV and PNG files");
  app.add_option("--reference", options.reference, "auto, modal or trapezoidal")
      ->check(CLI::IsMember({"auto", "modal", "trapezoidal"}));
  app.add_option("--max-modal-dofs", options.maxModalDofs, "Largest free-DOF count for the modal reference");
  app.add_option("--vertex", options.vertex, "Vertex of the displacement plot (default: chosen automatically)");
  app.add_option("--modes", options.modes,
                 "K: print the K lowest modes with omega*hL, omega*hS and the fast regions' shares, and the verdict")
      ->check(CLI::PositiveNumber);
  app.add_option("--kept-window", options.keptWindow,
                 "T0 T1: also print the motion-kept table for this time window (s); it always starts after the last "
                 "load window")
      ->expected(2);
  app.add_flag("--quick", options.quick, "At most 30 frames and one repeat (smoke test)");
  app.add_flag("--table", options.table, "Print the performance table of every scene in --models");
  app.add_option("--models", options.models, "Folder of scenes for --table (models/*/*.json)");
  app.add_option("--table-frames", options.tableFrames, "Frames per run for --table")->check(asyncfem::cli::atLeast(1));
  if (const std::optional<int> status = asyncfem::cli::parse(app, argc, argv, "integratorBenchmark")) return *status;
  return asyncfem::cli::run("integratorBenchmark", [&] {
    if (!options.table && options.scene.empty()) {
      throw asyncfem::cli::UsageError("a scene file is required (or --table)");
    }
    if (options.table) {
      return printPerformanceTable(options.models, options.tableFrames, options.repeats, options.out);
    }
    return runBenchmark(options);
  });
}
