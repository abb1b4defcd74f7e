// SPDX-License-Identifier: BSD-3-Clause
// suggestRegions: proposes fast regions and ratios for the asynchronous integrator from the
// materials and element sizes of a mesh, checks them against the lowest modes, and with
// --modes K prints the modal table of the given or proposed regions (see
// docs/asynchronous-integrator.md, "Which modes can async keep?").
#include <CLI/CLI.hpp>
#include <asyncfem/asyncIntegrator/autoRegions.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/threading.hpp>
#include <asyncfem/modalAnalysis/lowestModes.hpp>
#include <asyncfem/modalAnalysis/regionModes.hpp>
#include <asyncfem/sceneIO/asyncScene.hpp>
#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/sceneIO/simulation.hpp>
#include <asyncfem/volumetricMesh/readers.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <vector>

#include "commandLine.hpp"

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
  CLI::App app{
      "Proposes fast regions and ratios for the asynchronous integrator.\n"
      "Input: a scene (.json: its mesh, fixed vertices and integrator.timestep) or a mesh file."};
  std::string input, writePath;
  double largeTimestep = 0.0;
  AutoRegionOptions options;
  std::vector<std::string> fixedSets;
  bool json = false;
  int modeCount = 0;
  double frameRate = 0.0;
  bool noModalCheck = false;
  std::string massName = "consistent";
  app.add_option("input", input, "scene .json or mesh (.veg, .node/.ele, .msh)")->required();
  app.add_option("--dt", largeTimestep, "large timestep hL (default: the scene's integrator.timestep)")
      ->check(cli::positive());
  app.add_option("--target", options.targetOmegaH,
                 "absolute target for omega * h in every region (default: relative mode)")
      ->check(cli::positive());
  app.add_option("--relative", options.relativeThreshold,
                 "relative mode: elements above this multiple of the median element frequency become fast")
      ->check(cli::inRange(1.0001, 1e9))
      ->capture_default_str();
  app.add_option("--grow", options.growLayers, "vertex rings added around each region")
      ->check(cli::inRange(0, 100))
      ->capture_default_str();
  app.add_option("--max-ratio", options.maxRatio, "largest ratio m proposed")
      ->check(cli::inRange(1, 100000))
      ->capture_default_str();
  app.add_option("--fixed-set", fixedSets, "vertex set to treat as fixed (mesh input only)");
  app.add_option("--write", writePath, "write the regions as JSON, ready for integrator.options.regions");
  app.add_flag("--json", json, "print the proposal as JSON instead of a table");
  app.add_option("--modes", modeCount,
                 "print the K lowest modes with omega*hL, omega*hS and S share for the scene's regions "
                 "(or the proposal), and whether async can keep any of them")
      ->check(cli::inRange(1, 100000));
  app.add_option("--frame-rate", frameRate, "frames per second for the visibility test (default: the scene's, or 30)")
      ->check(cli::positive());
  app.add_flag("--no-modal-check", noModalCheck,
               "keep the proposal even when no visible mode lives in it (the check is on by default, as for "
               "\"regions\": \"auto\" in scenes)");
  app.add_option("--mass", massName, "mass matrix for a mesh input (scenes use their own)")
      ->check(CLI::IsMember({"consistent", "lumped"}))
      ->capture_default_str();
  if (const std::optional<int> status = cli::parse(app, argc, argv, "suggestRegions")) return *status;

  return cli::run("suggestRegions", [&] {
    std::shared_ptr<const TetMesh> mesh;
    FreeDofs freeDofs;
    MassType massType = massName == "lumped" ? MassType::lumped : MassType::consistent;
    std::vector<AsyncRegion> givenRegions;  // a scene's explicit regions
    bool corotational = false;
    std::optional<AutoRegionOptions> sceneAuto;  // an async scene with "regions": "auto"
    if (std::filesystem::path(input).extension() == ".json") {
      Scene scene = loadScene(input);
      if (!writePath.empty()) {
        std::vector<cli::NamedPath> inputs{{"the scene", input}};
        if (scene.mesh.source == Scene::MeshSource::file) inputs.push_back({"the mesh", scene.mesh.file});
        cli::refuseOutputOverInputs({"--write", writePath}, inputs, "write the regions to another file");
      }
      if (largeTimestep <= 0.0) largeTimestep = scene.integrator.timestep;
      if (frameRate <= 0.0) frameRate = scene.frames.rate;
      massType = scene.mass;
      corotational = scene.forceModel != Scene::ForceModelKind::linear;
      const Scene::IntegratorSettings integrator = scene.integrator;
      // Only the mesh and the constraints are needed: the problem, nothing assembled.
      const std::shared_ptr<const Problem> problem = buildProblem(scene);
      mesh = problem->sharedMesh();
      freeDofs = problem->freeDofs();
      const nlohmann::json* regions = integrator.options.is_object() && integrator.options.contains("regions")
                                          ? &integrator.options["regions"]
                                          : nullptr;
      if (integrator.name == "async" && regions && regions->is_array()) {
        givenRegions = parseAsyncOptions(scene, *mesh, freeDofs, integrator.options).regions;
      } else if (integrator.name == "async") {
        // What the simulator would run: the scene's own auto settings (command-line
        // options given explicitly replace them).
        Scene timed = scene;
        timed.integrator.timestep = largeTimestep;
        sceneAuto = parseAutoRegionOptions(integratorContext(timed), integrator.options);
      }
    } else {
      if (!writePath.empty()) {
        cli::refuseOutputOverInputs({"--write", writePath}, {{"the mesh", input}}, "write the regions to another file");
      }
      if (largeTimestep <= 0.0) throw Error("give the large timestep with --dt for a mesh input");
      MeshReadReport report;
      auto loaded = std::make_shared<TetMesh>(readMesh(input, {}, &report));
      for (const std::string& w : report.warnings) std::cerr << "suggestRegions: warning: " << w << "\n";
      std::vector<int> fixed;
      for (const std::string& set : fixedSets) {
        const std::vector<int> vertices = loaded->setVertices(set);
        fixed.insert(fixed.end(), vertices.begin(), vertices.end());
      }
      freeDofs = FreeDofs::fromFixedVertices(loaded->numVertices(), fixed);
      mesh = loaded;
    }
    if (frameRate <= 0.0) frameRate = 30.0;
    if (sceneAuto) {
      const AutoRegionOptions given = options;
      options = *sceneAuto;
      if (app.count("--target") > 0) options.targetOmegaH = given.targetOmegaH;
      if (app.count("--relative") > 0) options.relativeThreshold = given.relativeThreshold;
      if (app.count("--grow") > 0) options.growLayers = given.growLayers;
      if (app.count("--max-ratio") > 0) options.maxRatio = given.maxRatio;
      if (noModalCheck) options.modalCheck = false;
    } else {
      options.modalCheck = !noModalCheck;
    }
    options.largeTimestep = largeTimestep;
    options.frameRate = frameRate;
    if (sceneAuto && !json) {
      std::printf("settings: the scene's \"regions\": \"auto\" (integrator.options.auto%s), as the simulator runs it\n",
                  app.count("--target") + app.count("--relative") + app.count("--grow") + app.count("--max-ratio") > 0
                      ? ", with the options given here"
                      : "");
    }
    const VibrationMatrices matrices = vibrationMatrices(*mesh, massType);
    const AutoRegionProposal proposal = suggestRegions(*mesh, freeDofs, options, matrices.stiffness, matrices.mass);
    AutoRegionProposal withdrawn;
    withdrawn.regions = proposal.withdrawnRegions;
    if (json) {
      std::cout << nlohmann::json{{"largeTimestep", largeTimestep},
                                  {"target", proposal.targetOmegaH},
                                  {"largeRegionOmegaH", proposal.largeRegionMaxFrequency * largeTimestep},
                                  {"regions", proposalJson(proposal)},
                                  {"withdrawnRegions", proposalJson(withdrawn)},
                                  {"modalVerdict", proposal.modalReport ? proposal.modalReport->verdictText() : ""}}
                       .dump(2)
                << "\n";
    } else {
      std::printf("mesh: %d vertices, %d tets; hL = %g; target omega*h = %.3g%s\n", mesh->numVertices(),
                  mesh->numElements(), largeTimestep, proposal.targetOmegaH,
                  options.targetOmegaH > 0 ? "" : " (relative mode)");
      std::printf("L: max omega*hL = %.3g over the elements left in L\n",
                  proposal.largeRegionMaxFrequency * largeTimestep);
      if (proposal.regions.empty() && proposal.withdrawnRegions.empty()) {
        std::printf("no fast region needed: every element meets the target at hL\n");
      }
      std::printf("%-8s %8s %10s %10s %12s %14s %12s\n", "region", "ratio", "vertices", "tets", "interface",
                  "max omega", "omega*hS");
      for (const std::vector<ProposedRegion>* list : {&proposal.regions, &proposal.withdrawnRegions}) {
        for (const ProposedRegion& r : *list) {
          std::printf("%-8s %8d %10zu %10d %12d %14.4g %12.3g%s\n", r.region.name.c_str(), r.region.ratio,
                      r.region.vertices.size(), r.numElements, r.numInterfaceDofs, r.maxFrequency,
                      r.maxFrequency * largeTimestep / r.region.ratio,
                      list == &proposal.withdrawnRegions ? "  (withdrawn by the modal check)" : "");
        }
      }
      if (proposal.cost.evaluated) std::printf("cost check: %s\n", proposal.cost.decision.c_str());
      if (proposal.modalReport) {
        std::printf("modal check (%zu lowest modes, %.3g s): %s\n", proposal.modalReport->modes.size(),
                    proposal.modalSeconds, proposal.modalReport->verdictText().c_str());
        if (!proposal.withdrawnRegions.empty()) {
          std::printf(
              "no fast region proposed: the asynchronous integrator runs single-rate at hL "
              "(--no-modal-check keeps the regions)\n");
        }
      }
    }
    if (modeCount > 0) {
      // The given regions of the scene, else the proposal (withdrawn or not).
      const bool given = !givenRegions.empty();
      const std::vector<AsyncRegion> regions =
          given ? givenRegions : (proposal.regions.empty() ? withdrawn.asyncRegions() : proposal.asyncRegions());
      ModalOptions modal;
      modal.count = std::min(modeCount, freeDofs.numFree() - 1);
      const ModalResult modes = lowestModes(matrices.stiffness, matrices.mass, freeDofs, modal);
      std::ostream& out = json ? std::cerr : std::cout;
      out << "\nmodes of " << (given ? "the scene's regions" : "the proposed regions") << ": " << modal.count
          << " lowest of K phi = omega^2 M phi (" << freeDofs.numFree() << " free DOFs, linear K, "
          << (massType == MassType::lumped ? "lumped" : "consistent") << " M"
          << (corotational ? "; nonlinear scene: K is its rest tangent" : "") << ")\n";
      char line[160];
      std::snprintf(line, sizeof line,
                    "eigensolve: %.3g s (factorization %.3g s, %d solves, %d restarts, shift %.3g)\n",
                    modes.solveSeconds, modes.factorSeconds, modes.operatorApplications, modes.iterations, modes.shift);
      out << line;
      printRegionModeReport(out,
                            analyseRegionModes(modes, matrices.mass, modalRegions(regions), largeTimestep, frameRate));
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
    return 0;
  });
}
