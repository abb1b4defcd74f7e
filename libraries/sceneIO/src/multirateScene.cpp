// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/asyncIntegrator/uncoupledMultirate.hpp>
#include <asyncfem/sceneIO/asyncScene.hpp>
#include <asyncfem/sceneIO/jsonReader.hpp>
#include <asyncfem/sceneIO/multirateScene.hpp>
#include <string>

namespace asyncfem {

IntegratorFactory uncoupledMultirateIntegratorFactory() {
  return [](const Scene& scene, const TetMesh& mesh, DynamicSystem system,
            const nlohmann::json& options) -> std::unique_ptr<Integrator> {
    const std::string path = "integrator.options";
    if (!options.is_object()) {
      JsonObjectReader::failAt(scene.sourceName, path,
                               "expected an object, got " + JsonObjectReader::describe(options));
    }
    // Keys of the async integrator that have no meaning here: reject them by name rather
    // than silently ignoring a setting the user expects to matter.
    for (const char* key : {"coupling", "schur", "method", "recovery", "substepContact"}) {
      if (options.contains(key)) {
        JsonObjectReader::failAt(scene.sourceName, path + "." + key,
                                 "used by \"async\" only, not by \"multirate-uncoupled\"");
      }
    }
    UncoupledMultirateOptions solverOptions;
    nlohmann::json regionOptions = options;  // what parseAsyncOptions reads
    if (const auto it = options.find("compoundSolver"); it != options.end()) {
      const std::string name = JsonObjectReader::toString(*it, path + ".compoundSolver", scene.sourceName);
      if (name != "umfpack" && name != "eigen-lu") {
        JsonObjectReader::failAt(
            scene.sourceName, path + ".compoundSolver",
            "unknown value \"" + name + "\" (expected one of umfpack, eigen-lu: the system is unsymmetric)");
      }
      solverOptions.compoundSolver = parseSolverKind(name);
      regionOptions.erase("compoundSolver");
    }
    const AsyncSceneOptions parsed = parseAsyncOptions(scene, mesh, system.freeDofs, regionOptions);
    solverOptions.regionSolver = parsed.solver.regionSolver;
    return std::make_unique<UncoupledMultirate>(mesh, std::move(system), scene.integrator.timestep, parsed.regions,
                                                solverOptions);
  };
}

}  // namespace asyncfem
