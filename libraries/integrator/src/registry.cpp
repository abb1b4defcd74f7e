// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/integrator/factory.hpp>
#include <asyncfem/integrator/registry.hpp>
#include <asyncfem/settings/jsonReader.hpp>

namespace asyncfem {

void IntegratorRegistry::add(const std::string& name, IntegratorFactory factory, std::vector<std::string> optionKeys) {
  factories_[name] = std::move(factory);
  optionKeys_[name] = std::move(optionKeys);
}

const IntegratorFactory* IntegratorRegistry::find(const std::string& name) const {
  const auto it = factories_.find(name);
  return it == factories_.end() ? nullptr : &it->second;
}

const std::vector<std::string>& IntegratorRegistry::optionKeys(const std::string& name) const {
  static const std::vector<std::string> none;
  const auto it = optionKeys_.find(name);
  return it == optionKeys_.end() ? none : it->second;
}

std::vector<std::string> IntegratorRegistry::names() const {
  std::vector<std::string> result;
  for (const auto& [name, factory] : factories_) result.push_back(name);
  return result;
}

std::unique_ptr<Integrator> IntegratorRegistry::create(const std::string& name, IntegratorContext context,
                                                       const nlohmann::json& options) const {
  const std::string prefix = context.sourceName + ": ";
  const IntegratorFactory* factory = find(name);
  if (factory == nullptr) {
    std::string known;
    for (const std::string& n : names()) known += (known.empty() ? "" : ", ") + n;
    throw ValidationError(prefix + "integrator.name: unknown integrator \"" + name + "\" (known: " + known + ")");
  }
  const auto located = [&](const std::string& message) { return message.rfind(prefix, 0) == 0; };
  const bool implicitExternalForce = static_cast<bool>(context.system.externalForceJacobian);
  std::unique_ptr<Integrator> integrator;
  try {
    integrator = (*factory)(std::move(context), options);
  } catch (const TimestepError& error) {
    if (located(error.what())) throw;
    throw TimestepError(prefix + "integrator.timestep: " + error.what());
  } catch (const ValidationError& error) {
    if (located(error.what())) throw;
    throw ValidationError(prefix + "integrator: " + error.what());
  } catch (const NumericalError& error) {
    if (located(error.what())) throw;
    throw NumericalError(prefix + "integrator: " + error.what(), error.location());
  }
  if (implicitExternalForce && !integrator->linearizesExternalForce()) {
    throw ValidationError(prefix + "contact.implicit: integrator \"" + name +
                          "\" applies contact forces explicitly; implicit contact is linearized by \"backward-euler\" "
                          "and \"async\" (stable coupling, structured method) only (use one, or leave "
                          "contact.implicit out)");
  }
  return integrator;
}

std::vector<std::string> IntegratorRegistry::dropForeignOptions(const std::string& name,
                                                                nlohmann::json& options) const {
  std::vector<std::string> dropped;
  const std::vector<std::string>& known = optionKeys(name);
  if (known.empty() || !options.is_object()) return dropped;
  for (auto it = options.begin(); it != options.end();) {
    if (std::find(known.begin(), known.end(), it.key()) == known.end()) {
      dropped.push_back(it.key());
      it = options.erase(it);
    } else {
      ++it;
    }
  }
  std::sort(dropped.begin(), dropped.end());
  return dropped;
}

const std::vector<std::string>& singleRateOptionKeys() {
  static const std::vector<std::string> keys{"solver",
                                             "maxIterations",
                                             "contactIterations",
                                             "contactLowRank",
                                             "tolerance",
                                             "lineSearch",
                                             "rayleighStiffnessAtIterate",
                                             "reuseFactor",
                                             "pcgTolerance",
                                             "pcgSinglePrecision",
                                             "maxFrequency",
                                             "force"};
  return keys;
}

IntegratorOptions parseIntegratorOptions(const nlohmann::json& options, const std::string& optionsPath,
                                         const std::string& sourceName) {
  JsonObjectReader reader(options, optionsPath, sourceName);
  IntegratorOptions result;
  if (const auto solver = reader.optionalString("solver")) {
    try {
      result.solver = parseSolverKind(*solver);
    } catch (const Error& error) {
      reader.fail("solver", error.what());
    }
  }
  result.maxIterations = reader.integer("maxIterations", result.maxIterations, 1, 1000);
  result.tolerance = reader.number("tolerance", result.tolerance);
  if (!(result.tolerance > 0.0)) reader.fail("tolerance", "expected a number > 0");
  result.contactIterations = reader.integer("contactIterations", result.contactIterations, 1, 1000);
  result.contactLowRank = reader.boolean("contactLowRank", result.contactLowRank);
  result.lineSearch = reader.boolean("lineSearch", result.lineSearch);
  result.rayleighStiffnessAtIterate = reader.boolean("rayleighStiffnessAtIterate", result.rayleighStiffnessAtIterate);
  result.reuseFactor = reader.boolean("reuseFactor", result.reuseFactor);
  result.pcgTolerance = reader.number("pcgTolerance", result.pcgTolerance);
  if (!(result.pcgTolerance > 0.0 && result.pcgTolerance < 1.0))
    reader.fail("pcgTolerance", "expected a number in (0, 1)");
  result.pcgSinglePrecision = reader.boolean("pcgSinglePrecision", result.pcgSinglePrecision);
  result.maxFrequency = reader.number("maxFrequency", result.maxFrequency);
  if (result.maxFrequency < 0.0) reader.fail("maxFrequency", "expected a number >= 0 (0: estimate it)");
  result.force = reader.boolean("force", result.force);
  reader.finish();
  return result;
}

void registerSingleRateIntegrators(IntegratorRegistry& registry) {
  for (const std::string& name : integratorNames()) {
    registry.add(
        name,
        [name](IntegratorContext context, const nlohmann::json& options) {
          const IntegratorOptions parsed = parseIntegratorOptions(options, context.optionsPath, context.sourceName);
          return makeIntegrator(name, std::move(context.system), context.timestep, parsed);
        },
        singleRateOptionKeys());
  }
}

}  // namespace asyncfem
