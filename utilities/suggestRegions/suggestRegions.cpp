// SPDX-License-Identifier: BSD-3-Clause
// suggestRegions: proposes fast regions and ratios for the asynchronous integrator from the
// materials and element sizes of a mesh (see docs/asynchronous-integrator.md).
#include <asyncfem/core/threading.hpp>
#include <asyncfem/asyncIntegrator/autoRegions.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/sceneIO/simulation.hpp>
#include <asyncfem/volumetricMesh/readers.hpp>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>

namespace {

using namespace asyncfem;

nlohmann::json proposalJson(const AutoRegionProposal& proposal) {
  nlohmann::json regions = nlohmann::json::array();
  for (const ProposedRegion& r : proposal.regions) {
    regions.push_back({{"name", r.region.name}, {"ratio", r.region.ratio}, {"vertices", r.region.vertices}});
  }
  return regions;
}

}  // namespace

int main(int argc, char** argv) {
  asyncfem::preferPassiveThreadWaiting(argv);
  CLI::App app{"Proposes fast regions and ratios for the asynchronous integrator.\n"
               "Input: a scene (.json: its mesh, fixed vertices and integrator.timestep) or a mesh file."};
  std::string input, writePath;
  double largeTimestep = 0.0;
  AutoRegionOptions options;
  std::vector<std::string> fixedSets;
  bool json = false;
  app.add_option("input", input, "scene .json or mesh (.veg, .node/.ele, .msh)")->required();
  app.add_option("--dt", largeTimestep, "large timestep hL (default: the scene's integrator.timestep)")
      ->check(CLI::PositiveNumber);
  app.add_option("--target", options.targetOmegaH,
                 "absolute target for omega * h in every region (default: relative mode)")
      ->check(CLI::PositiveNumber);
  app.add_option("--relative", options.relativeThreshold,
                 "relative mode: elements above this multiple of the median element frequency become fast")
      ->check(CLI::Range(1.0001, 1e9))
      ->capture_default_str();
  app.add_option("--grow", options.growLayers, "vertex rings added around each region")
      ->check(CLI::Range(0, 100))
      ->capture_default_str();
  app.add_option("--max-ratio", options.maxRatio, "largest ratio m proposed")->check(CLI::Range(1, 100000))->capture_default_str();
  app.add_option("--fixed-set", fixedSets, "vertex set to treat as fixed (mesh input only)");
  app.add_option("--write", writePath, "write the regions as JSON, ready for integrator.options.regions");
  app.add_flag("--json", json, "print the proposal as JSON instead of a table");
  CLI11_PARSE(app, argc, argv);

  try {
    std::shared_ptr<const TetMesh> mesh;
    FreeDofs freeDofs;
    if (std::filesystem::path(input).extension() == ".json") {
      Scene scene = loadScene(input);
      if (largeTimestep <= 0.0) largeTimestep = scene.integrator.timestep;
      // Only the mesh and the constraints are needed: build with a single-rate integrator.
      scene.integrator.name = "backward-euler";
      scene.integrator.options = nlohmann::json::object();
      Simulation simulation = buildSimulation(scene);
      mesh = simulation.mesh;
      freeDofs = simulation.integrator->system().freeDofs;
    } else {
      if (largeTimestep <= 0.0) throw Error("give the large timestep with --dt for a mesh input");
      MeshReadReport report;
      auto loaded = std::make_shared<TetMesh>(readMesh(input, {}, &report));
      for (const std::string& w : report.warnings) std::cerr << "suggestRegions: warning: " << w << "\n";
      std::vector<int> fixed;
      for (const std::string& set : fixedSets) {
        const std::vector<int>& vertices = loaded->vertexSet(set);
        fixed.insert(fixed.end(), vertices.begin(), vertices.end());
      }
      freeDofs = FreeDofs::fromFixedVertices(loaded->numVertices(), fixed);
      mesh = loaded;
    }
    options.largeTimestep = largeTimestep;
    const AutoRegionProposal proposal = suggestRegions(*mesh, freeDofs, options);
    if (json) {
      std::cout << nlohmann::json{{"largeTimestep", largeTimestep},
                                  {"target", proposal.targetOmegaH},
                                  {"largeRegionOmegaH", proposal.largeRegionMaxFrequency * largeTimestep},
                                  {"regions", proposalJson(proposal)}}
                       .dump(2)
                << "\n";
    } else {
      std::printf("mesh: %d vertices, %d tets; hL = %g; target omega*h = %.3g%s\n", mesh->numVertices(),
                  mesh->numElements(), largeTimestep, proposal.targetOmegaH,
                  options.targetOmegaH > 0 ? "" : " (relative mode)");
      std::printf("L: max omega*hL = %.3g over the elements left in L\n", proposal.largeRegionMaxFrequency * largeTimestep);
      if (proposal.regions.empty()) std::printf("no fast region needed: every element meets the target at hL\n");
      std::printf("%-8s %8s %10s %10s %12s %14s %12s\n", "region", "ratio", "vertices", "tets", "interface", "max omega",
                  "omega*hS");
      for (const ProposedRegion& r : proposal.regions) {
        std::printf("%-8s %8d %10zu %10d %12d %14.4g %12.3g\n", r.region.name.c_str(), r.region.ratio,
                    r.region.vertices.size(), r.numElements, r.numInterfaceDofs, r.maxFrequency,
                    r.maxFrequency * largeTimestep / r.region.ratio);
      }
    }
    if (!writePath.empty()) {
      const std::filesystem::path target(writePath);
      const std::filesystem::path temporary = target.string() + ".tmp";
      {
        std::ofstream out(temporary);
        out << proposalJson(proposal).dump(1) << "\n";
        if (!out) throw Error("cannot write " + temporary.string());
      }
      std::filesystem::rename(temporary, target);
      if (!json) std::printf("regions written to %s\n", writePath.c_str());
    }
  } catch (const std::exception& e) {
    std::cerr << "suggestRegions: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
