// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// offlineSimulator's command line, as parsed (offlineSimulator.cpp adds the options).

#include <optional>
#include <string>

namespace offline {

struct CommandLine {
  std::string scene;
  std::optional<std::string> output;
  std::optional<std::string> integrator;
  std::optional<double> timestep;
  std::optional<int> stepsPerFrame;
  std::optional<int> frames;
  std::optional<std::string> vtuFolder;
  bool resume = false;
  int checkpointEvery = 0;
  double checkpointSeconds = 30.0;
  bool progress = false;
  bool quiet = false;
  bool noStabilityCheck = false;
  std::string backend = "local";
  std::string petscSolver = "cg-gamg";
  std::string petscOptions;
  std::string petscRegions = "owned";
  std::string petscElements = "distributed";
};

}  // namespace offline
