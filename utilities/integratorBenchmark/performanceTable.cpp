// SPDX-License-Identifier: BSD-3-Clause
#include "performanceTable.hpp"

#include <algorithm>
#include <asyncfem/asyncIntegrator/registration.hpp>
#include <asyncfem/benchmarkTools/benchmarkRun.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/sceneIO/asyncScene.hpp>
#include <asyncfem/warping/rotationStrainWarping.hpp>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "configurations.hpp"

namespace asyncfem::bench {

namespace {

namespace fs = std::filesystem;

std::string milliseconds(double seconds) {
  std::ostringstream out;
  out.precision(3);
  out << 1e3 * seconds;
  return out.str();
}

// Rotation-strain warping of every frame (what display would add per frame): ms per
// frame, median over repeats; "n/a" without frames.
std::string warpingMilliseconds(const Simulation& simulation, const Trajectory& frames, int repeats) {
  if (frames.empty()) return "n/a";
  RotationStrainWarping warper(*simulation.mesh, simulation.fixedVertices);
  std::vector<double> perRepeat;
  for (int repeat = 0; repeat < std::max(1, repeats); ++repeat) {
    Stopwatch watch;
    for (const Eigen::VectorXd& u : frames) warper.warp(u);
    perRepeat.push_back(watch.stop() / static_cast<double>(frames.size()));
  }
  return milliseconds(median(perRepeat));
}

// One row, or the reason the scene has none.
std::string tableRow(const fs::path& path, int frames, int repeats) {
  const Scene scene = loadScene(path);
  const std::string name = path.parent_path().filename().string() + "/" + path.filename().string();
  if (scene.integrator.name != "async") {
    return "";  // single-rate variants of a scene have no row of their own
  }
  if (scene.integrator.options.contains("regions") && scene.integrator.options["regions"].is_object()) {
    return "";  // run-time regions: no fixed m to compare single-rate at hS with
  }
  const int count = std::min(frames, scene.timing.frameCount);
  BenchmarkConfiguration async;
  async.integrator = "async";
  async.timestep = scene.timing.timestep;
  async.options = scene.integrator.options;
  async.label = "async";
  const Simulation simulation = buildSimulation(configuredScene(scene, async, 1));
  const AsyncSettings parsed =
      parseAsyncOptions(scene, *simulation.mesh, simulation.integrator->system().freeDofs, scene.integrator.options);
  std::ostringstream sizes, ratios;
  for (std::size_t i = 0; i < parsed.regions.size(); ++i) {
    sizes << (i ? ", " : "") << parsed.regions[i].vertices.size();
    ratios << (i ? ", " : "") << parsed.regions[i].ratio;
  }
  std::cerr << "integratorBenchmark --table: " << name
            << " (async, warping, backward Euler at hL and hS, schroeder2011)\n";
  const BenchmarkRun asyncRun = runConfiguration(scene, async, count, repeats);

  const std::string warping = warpingMilliseconds(simulation, asyncRun.frames, repeats);

  BenchmarkConfiguration large;
  large.integrator = "backward-euler";
  large.timestep = scene.timing.timestep;
  BenchmarkConfiguration small = large;
  small.timestep = scene.timing.timestep / largestRatio(parsed.regions);
  const BenchmarkRun largeRun = runConfiguration(scene, large, count, repeats);
  const BenchmarkRun smallRun = runConfiguration(scene, small, count, repeats);
  // Schroeder et al. 2011 on the same regions (its own keys only: the regions).
  BenchmarkConfiguration schroeder = async;
  schroeder.integrator = "schroeder2011";
  schroeder.label = "schroeder2011";
  schroeder.options = nlohmann::json{{"regions", scene.integrator.options.value("regions", nlohmann::json("auto"))}};
  const BenchmarkRun schroederRun = runConfiguration(scene, schroeder, count, repeats);
  auto cell = [](const BenchmarkRun& r) {
    if (r.completed) return milliseconds(r.medianSecondsPerFrame);
    if (r.failure.find("integrator.timestep") != std::string::npos) return std::string("refused (substep limit)");
    return "unstable (frame " + std::to_string(r.failedFrame) + ")";
  };
  std::ostringstream row;
  row << "| " << name << " | " << simulation.mesh->numVertices() << " | " << simulation.mesh->numElements() << " | "
      << sizes.str() << " | " << formatTimestep(scene.timing.timestep) << " | " << ratios.str() << " | "
      << (scene.forceModel == Scene::ForceModelKind::linear ? "linear" : "corotational") << " | " << cell(asyncRun)
      << " | " << warping << " | " << cell(largeRun) << " | " << cell(smallRun) << " | " << cell(schroederRun) << " | ";
  if (asyncRun.completed && smallRun.completed && asyncRun.medianSecondsPerFrame > 0.0) {
    std::ostringstream ratio;
    ratio.precision(3);
    ratio << smallRun.medianSecondsPerFrame / asyncRun.medianSecondsPerFrame << "x";
    row << ratio.str();
  } else {
    row << "n/a";
  }
  row << " |";
  return row.str();
}

}  // namespace

int printPerformanceTable(const std::string& modelsFolder, int frames, int repeats, const std::string& outFolder) {
  std::vector<fs::path> scenes;
  if (!fs::is_directory(modelsFolder)) throw Error(modelsFolder + ": not a folder (--models)");
  for (const fs::directory_entry& folder : fs::directory_iterator(modelsFolder)) {
    if (!folder.is_directory()) continue;
    for (const fs::directory_entry& file : fs::directory_iterator(folder.path())) {
      if (file.is_regular_file() && file.path().extension() == ".json") scenes.push_back(file.path());
    }
  }
  std::sort(scenes.begin(), scenes.end());
  std::ostringstream table;
  table << "Machine: " << machineDescription() << "\n";
  table << "Frames per run: up to " << frames << " (frame 0 excluded from the times), repeats: " << repeats
        << ", times are wall-clock milliseconds per frame (median over repeats). Warping: rotation-strain "
           "warping (libraries/warping) of every async frame.\n\n";
  table << "| scene | vertices | tets | \\|S_i\\| | hL (s) | m_i | forces | async | warping | single-rate hL | "
           "single-rate hS | schroeder2011 | hS / async |\n";
  table << "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  std::vector<std::string> skipped;
  for (const fs::path& path : scenes) {
    std::string row;
    try {
      row = tableRow(path, frames, repeats);
    } catch (const std::exception& error) {
      row = "| " + path.parent_path().filename().string() + "/" + path.filename().string() +
            " | error: " + error.what() + " |";
    }
    if (row.empty()) {
      skipped.push_back(path.parent_path().filename().string() + "/" + path.filename().string());
      continue;
    }
    table << row << "\n";
  }
  if (!skipped.empty()) {
    table << "\nNot in the table (single-rate scenes, and async scenes with run-time regions, which have no fixed m):";
    for (const std::string& name : skipped) table << " " << name;
    table << "\n";
  }
  std::cout << table.str();
  fs::create_directories(outFolder);
  std::ofstream(fs::path(outFolder) / "performance-table.md") << table.str();
  return 0;
}

}  // namespace asyncfem::bench
