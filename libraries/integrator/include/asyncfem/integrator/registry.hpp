// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/core/error.hpp>
#include <asyncfem/integrator/integrator.hpp>
#include <asyncfem/integrator/integratorOptions.hpp>
#include <asyncfem/stiffnessMatrix/assembler.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <functional>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace asyncfem {

/// What a registered factory gets to build its integrator from: the body (a
/// DynamicSystem), the mesh it was built on, the step and frame timing, and the few facts
/// of the problem that some integrators' options depend on. sourceName and optionsPath
/// only make error messages: "<sourceName>: <optionsPath>.key: ...".
struct IntegratorContext {
  std::shared_ptr<const TetMesh> mesh;
  DynamicSystem system;
  double timestep = 0.0;   ///< h (the large step of a multirate integrator)
  double frameRate = 0.0;  ///< frames per time unit (0: no frames, e.g. a library user)
  MassType massType = MassType::consistent;
  bool hasContact = false;  ///< the external force includes penalty contact
  std::string sourceName = "integrator";
  std::string optionsPath = "integrator.options";
};

/// Builds an integrator from a context and its options object (JSON). A factory reads
/// the keys it knows with a JsonObjectReader at context.optionsPath and rejects the rest,
/// so that errors name the key.
using IntegratorFactory =
    std::function<std::unique_ptr<Integrator>(IntegratorContext context, const nlohmann::json& options)>;

/// Integrator name -> factory, filled by the libraries that define integrators:
///
///     IntegratorRegistry registry;
///     registerSingleRateIntegrators(registry);   // library integrator
///     registerMultirateIntegrators(registry);    // library asyncIntegrator
///     auto integrator = registry.create("backward-euler", std::move(context), options);
///
/// A program adds its own with add() the same way.
class IntegratorRegistry {
 public:
  /// Adds (or replaces) the factory for name with the keys of its options object it reads
  /// (empty: not declared, so switchOptions() keeps every option).
  void add(const std::string& name, IntegratorFactory factory, std::vector<std::string> optionKeys = {});
  /// The factory for name, or nullptr.
  const IntegratorFactory* find(const std::string& name) const;
  /// The option keys declared for name (empty if none were, or name is unknown).
  const std::vector<std::string>& optionKeys(const std::string& name) const;
  /// Registered names, sorted.
  std::vector<std::string> names() const;

  /// Runs name's factory. Throws asyncfem::ValidationError
  /// "<sourceName>: integrator.name: unknown integrator ... (known: ...)" for an unknown
  /// name; errors of the factory that do not already start with "<sourceName>: " get that
  /// prefix and the key they concern: TimestepError "integrator.timestep", other
  /// ValidationErrors "integrator", NumericalErrors "integrator" (location kept).
  std::unique_ptr<Integrator> create(const std::string& name, IntegratorContext context,
                                     const nlohmann::json& options) const;

  /// Options belong to an integrator: removes from options (an object) the keys that
  /// `name` does not read (when it declares its keys) and returns them, sorted.
  std::vector<std::string> dropForeignOptions(const std::string& name, nlohmann::json& options) const;

 private:
  std::map<std::string, IntegratorFactory> factories_;
  std::map<std::string, std::vector<std::string>> optionKeys_;
};

/// The option keys every single-rate integrator reads (IntegratorOptions): solver,
/// maxIterations, tolerance, lineSearch, rayleighStiffnessAtIterate, reuseFactor,
/// pcgTolerance, maxFrequency, force.
const std::vector<std::string>& singleRateOptionKeys();
/// Reads those keys of options (a JSON object; unknown keys are errors naming them).
IntegratorOptions parseIntegratorOptions(const nlohmann::json& options, const std::string& optionsPath,
                                         const std::string& sourceName);
/// Adds "backward-euler", "trapezoidal", "central-differences" and "symplectic-euler".
void registerSingleRateIntegrators(IntegratorRegistry& registry);

}  // namespace asyncfem
