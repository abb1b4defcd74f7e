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
#include <sys/wait.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <asyncfem/asyncIntegrator/regionProposal.hpp>
#include <asyncfem/benchmarkTools/benchmarkReference.hpp>
#include <asyncfem/benchmarkTools/benchmarkRun.hpp>
#include <asyncfem/benchmarkTools/costInterpolation.hpp>
#include <asyncfem/benchmarkTools/errorMetrics.hpp>
#include <asyncfem/benchmarkTools/modalReference.hpp>
#include <asyncfem/benchmarkTools/multirateComparison.hpp>
#include <asyncfem/benchmarkTools/sceneReference.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/threading.hpp>
#include <asyncfem/modalAnalysis/lowestModes.hpp>
#include <asyncfem/modalAnalysis/regionModes.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>

#include "commandLine.hpp"
#include "configurations.hpp"
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
  std::vector<double> keptWindow;  ///< [t0, t1] for the motion-kept table; empty: after the last load window
  int modes = 0;                   ///< > 0: print the modal table of the scene's regions first
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

ReferenceKind referenceKind(const std::string& name) {
  return name == "modal"         ? ReferenceKind::modal
         : name == "trapezoidal" ? ReferenceKind::trapezoidal
                                 : ReferenceKind::automatic;
}

void writeResultsCsv(const fs::path& path, const std::vector<BenchmarkRun>& results,
                     const std::vector<VertexGroup>& groups) {
  std::ofstream out(path);
  out << "label,integrator,timestep,steps_per_frame,ratios,completed,failed_frame,seconds_per_frame_median,"
         "seconds_per_frame_min,repeats,setup_seconds,first_frame_seconds,factorizations_per_frame,solves_per_frame,"
         "factor_flops_per_frame,solve_flops_per_frame,factor_nonzeros";
  for (const VertexGroup& g : groups) out << ",error_" << g.name;
  out << "\n";
  out.precision(8);
  for (const BenchmarkRun& r : results) {
    out << '"' << r.configuration.label << "\"," << r.configuration.integrator << ',' << r.timestep << ','
        << r.stepsPerFrame << ",\"" << formatRatios(r.ratios) << "\"," << (r.completed ? 1 : 0) << ',' << r.failedFrame
        << ',' << r.medianSecondsPerFrame << ',' << r.minSecondsPerFrame << ',' << r.secondsPerFrame.size() << ','
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
// motion), against the exact modal solution, in the bands of motionBandEdges() for the
// scene's own step and the largest ratio of any run.
void writeMotionKept(const fs::path& path, const Scene& scene, const std::vector<BenchmarkRun>& results,
                     const ModalReference& modal, const BenchmarkReference& reference) {
  const double hL = scene.timing.timestep;
  const int maxRatio = largestRunRatio(results);
  const std::vector<double> edges = motionBandEdges(hL, maxRatio);
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
  for (const BenchmarkRun& r : results) {
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

// One row of the equal-cost / equal-error table and its CSV line.
void printEqualAnswer(const EqualAnswers& a, std::ostream& equalCsv) {
  const BenchmarkRun& r = *a.run;
  const double cost = runCost(r, a.costKind);
  const double error = r.errors.at(a.group);
  const std::string kind = toString(a.costKind);
  const std::string unit = a.costKind == CostKind::time ? " ms" : " Mflop";
  const double scale = a.costKind == CostKind::time ? 1e3 : 1e-6;
  if (!a.problem.empty()) {
    std::cout << "| " << r.configuration.label << " | " << a.group << " | " << kind << " | "
              << formatDouble(scale * cost, 3) << unit << " | " << formatDouble(error, 3) << " | n/a: " << a.problem
              << " | | | | |\n";
    equalCsv << '"' << r.configuration.label << "\"," << a.group << ',' << kind << ',' << cost << ',' << error
             << ",,,,,,,\"" << a.problem << "\"\n";
    return;
  }
  const double speedup = a.atEqualError.cost / cost;
  const std::string costMark = a.atEqualCost.extrapolated ? "*" : "";
  const std::string errorMark = a.atEqualError.extrapolated ? "*" : "";
  std::cout << "| " << r.configuration.label << " | " << a.group << " | " << kind << " | "
            << formatDouble(scale * cost, 3) << unit << " | " << formatDouble(error, 3) << " | "
            << formatDouble(a.atEqualCost.timestep, 3) << costMark << " | " << formatDouble(a.atEqualCost.error, 3)
            << costMark << " | " << formatDouble(a.atEqualError.timestep, 3) << errorMark << " | "
            << formatDouble(scale * a.atEqualError.cost, 3) << unit << errorMark << " | " << formatDouble(speedup, 3)
            << "x" << errorMark << " |\n";
  equalCsv << '"' << r.configuration.label << "\"," << a.group << ',' << kind << ',' << cost << ',' << error << ','
           << a.atEqualCost.timestep << ',' << a.atEqualCost.error << ',' << a.atEqualError.timestep << ','
           << a.atEqualError.cost << ',' << speedup << ','
           << ((a.atEqualCost.extrapolated || a.atEqualError.extrapolated) ? 1 : 0) << ",\n";
}

// Equal cost and equal error against single-rate backward Euler, for the first fast
// region's group (when there is one) and all vertices.
void printEqualAnswers(const std::vector<BenchmarkRun>& results, const std::vector<VertexGroup>& groups,
                       const fs::path& outFolder) {
  std::vector<std::string> answerGroups{"all"};
  if (groups.size() > 1) answerGroups.insert(answerGroups.begin(), groups.front().name);
  std::cout << "\n## Equal cost and equal error against single-rate backward Euler\n\n"
               "Interpolation: piecewise linear in log-log between the measured backward Euler runs "
               "(cost against h and error against h; extended along the end segment outside the measured "
               "range, marked *). Cost = median wall time per frame, or factor + solve flops per frame.\n\n";
  std::cout << "| configuration | error of | cost | multirate cost | multirate error | BE h at equal cost | BE error "
               "there | BE h at equal error | BE cost there | speed-up at equal error |\n";
  std::cout << "|---|---|---|---|---|---|---|---|---|---|\n";
  std::ofstream equalCsv(outFolder / "equal-cost-error.csv");
  equalCsv << "label,group,cost_kind,multirate_cost,multirate_error,equal_cost_timestep,equal_cost_error,"
              "equal_error_timestep,equal_error_cost,speedup_at_equal_error,extrapolated,problem\n";
  equalCsv.precision(8);
  for (const EqualAnswers& a : equalAnswers(results, answerGroups)) printEqualAnswer(a, equalCsv);
}

/// A figure's curves in long form, series,time,value (what scripts/plot-benchmark.py reads).
class SeriesCsv {
 public:
  explicit SeriesCsv(const fs::path& path) : out_(path) {
    out_ << "series,time,value\n";
    out_.precision(10);
  }
  void add(const std::string& series, const std::vector<double>& times, const std::vector<double>& values) {
    for (std::size_t i = 0; i < times.size() && i < values.size(); ++i) {
      out_ << '"' << series << "\"," << times[i] << ',' << values[i] << "\n";
    }
  }

 private:
  std::ofstream out_;
};

void writeVertexCsv(const fs::path& path, const std::vector<BenchmarkRun>& results, const BenchmarkReference& reference,
                    const Scene& scene, int vertex) {
  SeriesCsv csv(path);
  csv.add("reference", frameTimes(scene, static_cast<int>(reference.frames.size())),
          vertexDisplacementNorms(reference.frames, vertex));
  for (const BenchmarkRun& r : results) {
    if (!r.configuration.plotTrajectory || r.frames.empty()) continue;
    csv.add(r.configuration.label, frameTimes(scene, static_cast<int>(r.frames.size())),
            vertexDisplacementNorms(r.frames, vertex));
  }
}

/// The table of motion kept at `vertex` after the loads end (keptMotionComparison), for
/// every configuration, and for each multirate one what single-rate backward Euler keeps
/// at the same wall time and at the same flops per frame.
void printMotionKept(const std::vector<BenchmarkRun>& results, const Trajectory& reference, const Scene& scene,
                     const Simulation& baseline, int vertex, const std::vector<double>& window) {
  const auto [release, until] = keptMotionWindow(sceneLoad(scene, baseline), window);
  const std::vector<double> times = frameTimes(scene, static_cast<int>(reference.size()));
  std::cout << "\n## Motion kept at vertex " << vertex << " after the loads end (" << formatDouble(release, 3)
            << " s < t" << (std::isfinite(until) ? " <= " + formatDouble(until, 3) + " s" : "")
            << ")\n\nRMS of the vertex's displacement about its equilibrium, over the frames after the last load "
               "window, divided by the reference's (phase ignored). BE columns: single-rate backward Euler "
               "interpolated to the same wall time / flops per frame (* extrapolated).\n\n"
               "| configuration | time/frame (ms) | kept | BE kept at equal time | ratio | BE kept at equal flops | "
               "ratio |\n|---|---|---|---|---|---|---|\n";
  for (const KeptMotion& row : keptMotionComparison(results, reference, times, release, until, vertex)) {
    const BenchmarkRun& r = *row.run;
    std::cout << "| " << r.configuration.label << " | " << formatDouble(1e3 * r.medianSecondsPerFrame, 3) << " | "
              << formatDouble(row.kept, 3) << " |";
    if (!row.compared) {
      std::cout << " | | | |\n";
      continue;
    }
    for (const std::optional<EqualCostAnswer>& answer : {row.atEqualTime, row.atEqualFlops}) {
      if (!answer) {
        std::cout << " n/a | |";
        continue;
      }
      const std::string mark = answer->extrapolated ? "*" : "";
      std::cout << " " << formatDouble(answer->error, 3) << mark << " | " << formatDouble(row.kept / answer->error, 3)
                << "x" << mark << " |";
    }
    std::cout << "\n";
  }
}

/// The figure of the paper's Figures 4 and 7 for one vertex: the signed displacement
/// coordinate that moves most in the reference, over time, for the reference and the runs
/// of equalCostFigureRuns(). Nothing is drawn without a completed multirate run and two
/// backward Euler runs.
void writeVertexEqualCostCsv(const fs::path& path, const std::vector<BenchmarkRun>& results,
                             const BenchmarkReference& reference, const Scene& scene, int vertex,
                             const std::vector<int>& sceneRatios) {
  const EqualCostFigureRuns figure = equalCostFigureRuns(results, sceneRatios);
  if (!figure.multirate || !figure.coarse || !figure.equalCost) return;
  int coordinate = 0;
  Eigen::Vector3d energy = Eigen::Vector3d::Zero();
  for (const Eigen::VectorXd& u : reference.frames) energy += u.segment<3>(3 * vertex).cwiseAbs2();
  energy.maxCoeff(&coordinate);
  const auto component = [&](const Trajectory& frames) {
    std::vector<double> values;
    for (const Eigen::VectorXd& u : frames) values.push_back(u[3 * vertex + coordinate]);
    return values;
  };
  SeriesCsv csv(path);
  const char* axis = coordinate == 0 ? "x" : coordinate == 1 ? "y" : "z";
  csv.add(std::string("exact (u_") + axis + ")", frameTimes(scene, static_cast<int>(reference.frames.size())),
          component(reference.frames));
  const std::vector<std::pair<const BenchmarkRun*, std::string>> runs{
      {figure.coarse, figure.coarse->configuration.label + " (largest step)"},
      {figure.equalCost, figure.equalCost->configuration.label + " (nearest wall time)"},
      {figure.multirate, figure.multirate->configuration.label}};
  for (const auto& [run, label] : runs) {
    csv.add(label, frameTimes(scene, static_cast<int>(run->frames.size())), component(run->frames));
  }
}

// The regions the scene itself runs with, resolved as the integrator resolves them
// ("auto" included); none for a single-rate scene.
std::vector<AsyncRegion> sceneRegions(const Scene& scene, const Simulation& baseline) {
  BenchmarkConfiguration own;
  own.integrator = scene.integrator.name;
  own.timestep = scene.timing.timestep;
  own.options = scene.integrator.options;
  return configurationRegions(scene, baseline, own);
}

std::vector<int> ratiosOf(const std::vector<AsyncRegion>& regions) {
  std::vector<int> ratios;
  for (const AsyncRegion& region : regions) ratios.push_back(region.ratio);
  return ratios;
}

/// The K lowest modes of the scene (linear K, the scene's mass) with omega hL, omega hS and
/// the share of each fast region, and the verdict: which modes async can keep here
/// (docs/asynchronous-integrator.md, "Which modes can async keep?").
void printSceneModes(const Scene& scene, const Simulation& baseline, int count) {
  const FreeDofs& freeDofs = baseline.integrator->system().freeDofs;
  const std::vector<AsyncRegion> regions = sceneRegions(scene, baseline);
  const VibrationMatrices matrices = vibrationMatrices(*baseline.mesh, scene.mass);
  ModalOptions modal;
  modal.count = std::min(count, freeDofs.numFree() - 1);
  const ModalResult modes = lowestModes(matrices.stiffness, matrices.mass, freeDofs, modal);
  std::cout << "\n## The " << modal.count << " lowest modes and the scene's fast regions (eigensolve "
            << formatDouble(modes.solveSeconds, 3) << " s)\n\n";
  printRegionModeReport(std::cout, analyseRegionModes(modes, matrices.mass, modalRegions(regions),
                                                      scene.timing.timestep, scene.timing.frameRate));
}

// The configurations of the command line (file, then specs), else the scene's defaults.
// Every one is built once before the reference is computed (the expensive part), so a bad
// one (unknown integrator or option, a timestep that does not divide the frame interval)
// fails at once; a timestep the integrator refuses as unstable is run and reported.
std::vector<BenchmarkConfiguration> configurationsOf(const CommandLine& options, const Scene& scene,
                                                     const Simulation& baseline) {
  std::vector<BenchmarkConfiguration> configs;
  if (!options.configsFile.empty()) configs = readConfigurations(options.configsFile, scene, baseline);
  for (const std::string& spec : options.configSpecs) {
    configs.push_back(parseConfigurationSpec(spec, scene, baseline));
  }
  if (configs.empty()) configs = defaultConfigurations(scene, baseline);
  for (const BenchmarkConfiguration& c : configs) {
    try {
      (void)buildSimulation(configuredScene(scene, c, 1));
    } catch (const TimestepError&) {
      // A step its integrator refuses is a result (a configuration failing before its
      // first frame, with the message), not a bad command line.
    } catch (const Error& error) {
      throw Error("configuration \"" + c.label + "\": " + error.what());
    }
  }
  return configs;
}

// Every configuration run and its errors per group against the reference.
std::vector<BenchmarkRun> runAll(const std::vector<BenchmarkConfiguration>& configs, const Scene& scene, int frames,
                                 int repeats, const std::vector<VertexGroup>& groups,
                                 const BenchmarkReference& reference) {
  std::vector<BenchmarkRun> results;
  for (std::size_t k = 0; k < configs.size(); ++k) {
    std::cerr << "integratorBenchmark: [" << (k + 1) << "/" << configs.size() << "] " << configs[k].label << "\n";
    // Long explicit runs (thousands of steps per frame) are timed once.
    const bool longRun =
        configs[k].stepsPerFrame > 0 && static_cast<long long>(configs[k].stepsPerFrame) * frames > 20000;
    BenchmarkRun r = runConfiguration(scene, configs[k], frames, longRun ? 1 : repeats);
    for (const VertexGroup& g : groups) r.errors[g.name] = relativeL2Error(r.frames, reference.frames, g);
    results.push_back(std::move(r));
  }
  return results;
}

void printResults(const std::vector<BenchmarkRun>& results, const std::vector<VertexGroup>& groups) {
  std::cout << "\n| configuration | h | m | time/frame (ms) | factor./frame | solves/frame | Mflop/frame |";
  for (const VertexGroup& g : groups) std::cout << " error " << g.name << " |";
  std::cout << "\n|---|---|---|---|---|---|---|";
  for (std::size_t g = 0; g < groups.size(); ++g) std::cout << "---|";
  std::cout << "\n";
  for (const BenchmarkRun& r : results) {
    std::cout << "| " << r.configuration.label << " | " << formatTimestep(r.timestep) << " | "
              << (r.ratios.empty() ? "-" : formatRatios(r.ratios)) << " | "
              << formatDouble(1e3 * r.medianSecondsPerFrame, 3) << " | " << formatDouble(r.factorizationsPerFrame, 3)
              << " | " << formatDouble(r.solvesPerFrame, 4) << " | " << formatDouble(1e-6 * r.flopsPerFrame(), 4)
              << " |";
    for (const VertexGroup& g : groups) std::cout << " " << formatDouble(r.errors.at(g.name), 3) << " |";
    std::cout << "\n";
  }
  for (const BenchmarkRun& r : results) {
    if (!r.completed) {
      std::cout << "\nUNSTABLE: " << r.configuration.label << " stopped at frame " << r.failedFrame << ": " << r.failure
                << "\n";
    }
  }
}

// What the plots need besides the runs.
struct PlotInputs {
  const Scene& scene;
  const BenchmarkReference& reference;
  const std::vector<VertexGroup>& groups;
  std::vector<int> sceneRatios;
  int vertex;
  std::string sceneName;
};

/// scripts/plot-benchmark.py as the build (or an install) puts it next to this program.
fs::path plotScript() {
  std::error_code error;
  const fs::path self = fs::read_symlink("/proc/self/exe", error);
  return error ? fs::path("plot-benchmark.py") : self.parent_path() / "plot-benchmark.py";
}

/// The figures' data as CSV, and the figures drawn from it by scripts/plot-benchmark.py
/// with matplotlib (PNG and PDF); without matplotlib (or python3) a message says how to
/// get them and the CSV files stay.
void writePlots(const fs::path& outFolder, const std::vector<BenchmarkRun>& results, const PlotInputs& in) {
  writeVertexCsv(outFolder / "vertex-displacement.csv", results, in.reference, in.scene, in.vertex);
  const fs::path focus = outFolder / "vertex-equal-cost.csv";
  // An older run's figure must not survive a run that draws none.
  for (const char* stale : {"vertex-equal-cost.csv", "vertex-equal-cost.png", "vertex-equal-cost.pdf"}) {
    fs::remove(outFolder / stale);
  }
  writeVertexEqualCostCsv(focus, results, in.reference, in.scene, in.vertex, in.sceneRatios);
  const fs::path script = plotScript();
  const std::string python = fs::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";
  const std::string drawLater = "draw them later with: " + python + " scripts/plot-benchmark.py " + outFolder.string();
  if (!fs::exists(script)) {
    std::cout << "\nNo figures: " << script.string() << " is missing; the CSV files are written, " << drawLater << "\n";
    return;
  }
  std::cout << "\nFigures (vertex " << in.vertex << ", matplotlib):\n" << std::flush;
  const std::string command =
      "'" + python + "' '" + script.string() + "' '" + outFolder.string() + "' --title '" + in.sceneName + "'";
  const int status = std::system(command.c_str());
  const int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  if (code == 3) {
    std::cout << "No figures: matplotlib is missing (Debian: sudo apt-get install python3-matplotlib, or "
                 "scripts/install-deps.sh); the CSV files are written, "
              << drawLater << "\n";
  } else if (code != 0) {
    std::cout << "No figures: " << script.string() << " failed (exit status " << code
              << "); the CSV files are written\n";
  }
}

int runBenchmark(const CommandLine& options) {
  const Scene scene = loadScene(options.scene);
  const int frames = options.quick ? std::min(options.frames.value_or(scene.timing.frameCount), 30)
                                   : options.frames.value_or(scene.timing.frameCount);
  const int repeats = options.quick ? 1 : options.repeats;
  const fs::path outFolder(options.out);
  fs::create_directories(outFolder);
  // A single-rate build of the scene gives the mesh and matrices.
  BenchmarkConfiguration baselineConfig;
  baselineConfig.stepsPerFrame = 1;
  const Simulation baseline = buildSimulation(configuredScene(scene, baselineConfig, 1));
  const std::vector<BenchmarkConfiguration> configs = configurationsOf(options, scene, baseline);

  std::cout << "# integratorBenchmark: " << options.scene << "\n\n";
  std::cout << "Machine: " << machineDescription() << "\n";
  std::cout << "Mesh: " << baseline.mesh->numVertices() << " vertices, " << baseline.mesh->numElements() << " tets, "
            << baseline.integrator->system().freeDofs.numFree() << " free DOFs; " << frames << " frames at "
            << scene.timing.frameRate << " per s; " << repeats
            << " repeats (time per frame: median over repeats of the mean over frames 1.., frame 0 is warm-up)\n";
  std::cout.flush();

  const BenchmarkReference reference =
      computeReference(scene, baseline, configs, frames, referenceKind(options.reference), options.maxModalDofs);
  std::cout << "Reference: " << reference.description << "\n";
  if (options.modes > 0) printSceneModes(scene, baseline, options.modes);
  const std::vector<VertexGroup> groups = errorGroups(scene, baseline, configs);
  const std::vector<BenchmarkRun> results = runAll(configs, scene, frames, repeats, groups, reference);
  printResults(results, groups);
  writeResultsCsv(outFolder / "results.csv", results, groups);
  if (reference.modal) writeMotionKept(outFolder / "motion-kept.csv", scene, results, *reference.modal, reference);
  printEqualAnswers(results, groups, outFolder);

  const int vertex = options.vertex.value_or(chooseVertex(reference.frames, groups, baseline.mesh->numVertices()));
  printMotionKept(results, reference.frames, scene, baseline, vertex, {});
  if (!options.keptWindow.empty())
    printMotionKept(results, reference.frames, scene, baseline, vertex, options.keptWindow);
  writePlots(outFolder, results,
             {scene, reference, groups, ratiosOf(sceneRegions(scene, baseline)), vertex,
              fs::path(options.scene).stem().string()});
  std::cout << "Wrote " << (outFolder / "results.csv").string() << " and "
            << (outFolder / "equal-cost-error.csv").string() << "\n";
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
