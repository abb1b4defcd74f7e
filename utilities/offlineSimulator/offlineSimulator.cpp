// SPDX-License-Identifier: BSD-3-Clause
// offlineSimulator: runs a scene file and stores its frames.
//
//   offlineSimulator SCENE.json [--output FILE.afsim] [--integrator NAME] [--dt H]
//                    [--frames N] [--vtu FOLDER] [--progress] [--quiet]
//
// Frames go to one .afsim file (docs/simulation-output.md), optionally one .vtu per
// frame; progress on stderr, the run summary on stdout. Errors print
// "offlineSimulator: <message>" on stderr and exit with status 1. What it prints is
// described in docs/scene-format.md, section "Running a scene".
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/sceneIO/simulation.hpp>
#include <asyncfem/simulationIO/simulationFile.hpp>
#include <asyncfem/volumetricMesh/writers.hpp>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>

#include "progress.hpp"

namespace {

namespace fs = std::filesystem;
using asyncfem::offline::ProgressReporter;
using asyncfem::offline::ProgressStyle;

struct CommandLine {
  std::string scene;
  std::optional<std::string> output;
  std::optional<std::string> integrator;
  std::optional<double> timestep;
  std::optional<int> frames;
  std::optional<std::string> vtuFolder;
  bool progress = false;
  bool quiet = false;
};

// Command-line values replace the scene's; paths given here are relative to the
// current folder, not the scene's.
void applyOverrides(const CommandLine& options, asyncfem::Scene& scene) {
  if (options.output) {
    scene.output.file = *options.output;
  }
  if (options.integrator) {
    scene.integrator.name = *options.integrator;
  }
  if (options.timestep) {
    scene.integrator.timestep = *options.timestep;
  }
  if (options.frames) {
    scene.frames.count = *options.frames;
  }
  if (options.vtuFolder) {
    scene.output.vtuFolder = *options.vtuFolder;
  }
  if (scene.output.file.empty()) {
    throw asyncfem::Error("no output file: set output.file in " + scene.sourceName + " or pass --output FILE");
  }
}

std::string vtuName(int frame) {
  char name[32];
  std::snprintf(name, sizeof(name), "frame_%05d.vtu", frame);
  return name;
}

std::string milliseconds(double seconds, int frames) {
  char text[32];
  std::snprintf(text, sizeof(text), "%9.3f ms", 1000.0 * seconds / frames);
  return text;
}

void printSummary(const asyncfem::Scene& scene, const asyncfem::Simulation& simulation,
                  const asyncfem::IntegratorStats& before, double setupSeconds, double loopSeconds,
                  double outputSeconds, std::int64_t outputBytes) {
  const asyncfem::IntegratorStats& after = simulation.integrator->stats();
  const int frames = simulation.numFrames;
  const double forces = after.forceSeconds - before.forceSeconds;
  const double assembly = after.assemblySeconds - before.assemblySeconds;
  const double factorization = after.factorizationSeconds - before.factorizationSeconds;
  const double solve = after.solveSeconds - before.solveSeconds;
  const double other = loopSeconds - forces - assembly - factorization - solve - outputSeconds;
  const long long steps = after.steps - before.steps;

  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(3);
  out << "offlineSimulator: " << scene.sourceName << ": " << frames << " frames, " << steps
      << " steps of h = " << std::defaultfloat << simulation.timestep << " (" << simulation.stepsPerFrame
      << " per frame), " << std::fixed << (setupSeconds + loopSeconds) << " s\n";
  out << "  mesh        " << simulation.mesh->numVertices() << " vertices, " << simulation.mesh->numElements()
      << " elements, " << simulation.fixedVertices.size() << " fixed vertices\n";
  out << "  model       "
      << (scene.forceModel == asyncfem::Scene::ForceModelKind::linear
              ? "linear"
              : (scene.tangent == asyncfem::Scene::Tangent::exact ? "corotational (exact tangent)"
                                                                  : "corotational (simple tangent)"))
      << ", " << (scene.mass == asyncfem::MassType::lumped ? "lumped" : "consistent") << " mass, integrator "
      << simulation.integrator->name() << "\n";
  out << "  setup       " << setupSeconds << " s (mesh, matrices, first factorization: " << before.factorizationSeconds
      << " s)\n";
  out << "  per frame   " << milliseconds(loopSeconds, frames) << "   (total " << loopSeconds << " s)\n";
  out << "    forces        " << milliseconds(forces, frames) << "\n";
  out << "    assembly      " << milliseconds(assembly, frames) << "\n";
  out << "    factorization " << milliseconds(factorization, frames) << "   ("
      << (after.factorizations - before.factorizations) << " factorizations in the run)\n";
  out << "    solve         " << milliseconds(solve, frames) << "   ("
      << (after.solvedRightHandSides - before.solvedRightHandSides) << " right-hand sides)\n";
  out << "    output        " << milliseconds(outputSeconds, frames) << "\n";
  out << "    other         " << milliseconds(other, frames) << "   (vector updates, loads, state checks)\n";
  out << "  skipped:\n";
  for (const std::string& item : after.skipped) {
    out << "    - " << item << "\n";
  }
  for (const std::string& item : simulation.skipped) {
    out << "    - " << item << "\n";
  }
  out << "  output      " << scene.output.file.string() << " (" << frames << " frames, " << outputBytes << " bytes)";
  if (!scene.output.vtuFolder.empty()) {
    out << ", .vtu files in " << scene.output.vtuFolder.string();
  }
  out << "\n";
  std::cout << out.str() << std::flush;
}

int run(int argc, char** argv) {
  CLI::App app{
      "Runs a scene file (docs/scene-format.md) and writes its frames to an .afsim file "
      "(docs/simulation-output.md)."};
  CommandLine options;
  app.add_option("scene", options.scene, "Scene file (.json)")->required();
  app.add_option("-o,--output", options.output,
                 "Output .afsim file (replaces output.file; truncated at the start of the run)");
  app.add_option("--integrator", options.integrator, "Integrator name (replaces integrator.name)");
  app.add_option("--dt", options.timestep, "Timestep h (replaces integrator.timestep)")->check(CLI::PositiveNumber);
  app.add_option("--frames", options.frames, "Number of frames (replaces frames.count)")->check(CLI::PositiveNumber);
  app.add_option("--vtu", options.vtuFolder,
                 "Also write FOLDER/frame_NNNNN.vtu per frame (replaces output.vtu.folder)");
  app.add_flag("--progress", options.progress, "Draw the progress bar even when stderr is not a terminal");
  app.add_flag("-q,--quiet", options.quiet, "Print nothing but errors");
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "offlineSimulator: " << e.what() << " (see --help)\n";
    return 2;
  }

  asyncfem::Stopwatch setupWatch;
  setupWatch.start();
  asyncfem::Scene scene = asyncfem::loadScene(options.scene);
  applyOverrides(options, scene);
  asyncfem::Simulation simulation = asyncfem::buildSimulation(scene);
  const double setupSeconds = setupWatch.stop();
  const asyncfem::IntegratorStats statsAfterSetup = simulation.integrator->stats();

  // The output file is created (truncated) only once the scene has been built, so a
  // scene error leaves an existing file alone; from here on it holds this run's frames.
  if (scene.output.file.has_parent_path()) {
    fs::create_directories(scene.output.file.parent_path());
  }
  if (!scene.output.vtuFolder.empty()) {
    fs::create_directories(scene.output.vtuFolder);
  }
  asyncfem::SimulationFileHeader header;
  header.numVertices = simulation.mesh->numVertices();
  header.frameInterval = simulation.frameInterval;
  header.timestep = simulation.timestep;
  header.hasVelocities = scene.output.velocities;
  asyncfem::SimulationWriter writer(scene.output.file, header, asyncfem::SimulationWriter::Options{scene.output.sync});

  ProgressStyle style = ProgressStyle::lines;
  if (options.quiet) {
    style = ProgressStyle::none;
  } else if (options.progress || ::isatty(STDERR_FILENO) != 0) {
    style = ProgressStyle::bar;
  }
  ProgressReporter progress(style, simulation.numFrames);

  asyncfem::Stopwatch loopWatch;
  asyncfem::Stopwatch outputWatch;
  loopWatch.start();
  int frame = 0;
  try {
    for (; frame < simulation.numFrames; ++frame) {
      asyncfem::advanceFrame(simulation, frame);
      {
        const asyncfem::ScopedTimer timer(outputWatch);
        const asyncfem::Integrator& integrator = *simulation.integrator;
        if (header.hasVelocities) {
          writer.appendFrame(integrator.time(), integrator.displacement(), integrator.velocity());
        } else {
          writer.appendFrame(integrator.time(), integrator.displacement());
        }
        if (!scene.output.vtuFolder.empty() && frame % scene.output.vtuEvery == 0) {
          asyncfem::writeVtu(scene.output.vtuFolder / vtuName(frame), *simulation.mesh, integrator.displacement());
        }
      }
      progress.update(frame + 1);
    }
  } catch (const asyncfem::Error& error) {
    progress.finish();
    // The frames before the failing one are complete, checksummed records.
    throw asyncfem::Error(std::string(error.what()) + "; the " + std::to_string(writer.numFrames()) +
                          " frames before it are kept in " + scene.output.file.string());
  }
  const double loopSeconds = loopWatch.stop();
  progress.finish();
  writer.close();

  if (!options.quiet) {
    const auto bytes = static_cast<std::int64_t>(fs::file_size(scene.output.file));
    printSummary(scene, simulation, statsAfterSetup, setupSeconds, loopSeconds, outputWatch.totalSeconds(), bytes);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "offlineSimulator: " << e.what() << "\n";
    return 1;
  }
}
