// SPDX-License-Identifier: BSD-3-Clause
#include "configurations.hpp"

#include <algorithm>
#include <asyncfem/asyncIntegrator/registration.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/integrator/stableTimestep.hpp>
#include <asyncfem/sceneIO/asyncScene.hpp>
#include <cmath>
#include <fstream>
#include <optional>
#include <sstream>
#include <thread>

namespace asyncfem::bench {

namespace {

// Regions of the scene's own integrator options, or "auto".
nlohmann::json sceneRegions(const Scene& scene) {
  if (isMultirate(scene.integrator.name) && scene.integrator.options.contains("regions")) {
    return scene.integrator.options["regions"];
  }
  return "auto";
}

// The explicit regions of an options object, resolved on the baseline's mesh as the
// integrator reads them; nullopt for "auto" or no regions.
std::optional<std::vector<AsyncRegion>> explicitRegions(const nlohmann::json& options, const Scene& scene,
                                                        const Simulation& baseline) {
  if (!options.is_object() || !options.contains("regions") || !options["regions"].is_array()) return std::nullopt;
  const nlohmann::json regionsOnly = {{"regions", options["regions"]}};
  return parseAsyncOptions(scene, *baseline.mesh, baseline.integrator->system().freeDofs, regionsOnly).regions;
}

// Every explicit region of options at this ratio (written back by the regions codec).
void setRatio(nlohmann::json& options, int ratio, const std::string& where, const Scene& scene,
              const Simulation& baseline) {
  std::optional<std::vector<AsyncRegion>> regions = explicitRegions(options, scene, baseline);
  if (!regions) {
    throw ValidationError(where +
                          ": \"ratio\" needs explicit regions (the scene's or the configuration's), not \"auto\"");
  }
  for (AsyncRegion& region : *regions) region.ratio = ratio;
  options["regions"] = asyncRegionsJson(*regions);
}

// Multirate configurations without regions inherit the scene's.
void completeOptions(BenchmarkConfiguration& configuration, const Scene& scene) {
  if (isMultirate(configuration.integrator) && !configuration.options.contains("regions")) {
    configuration.options["regions"] = sceneRegions(scene);
    if (scene.integrator.options.contains("auto") && configuration.options["regions"] == "auto") {
      configuration.options["auto"] = scene.integrator.options["auto"];
    }
  }
}

std::string defaultLabel(const BenchmarkConfiguration& c, const Scene& scene, const Simulation& baseline) {
  std::ostringstream out;
  out << c.integrator;
  if (c.stepsPerFrame > 0) {
    out << " spf=" << c.stepsPerFrame;
  } else {
    out << " h=" << c.timestep;
  }
  if (isMultirate(c.integrator)) {
    const std::optional<std::vector<AsyncRegion>> regions = explicitRegions(c.options, scene, baseline);
    if (regions && !regions->empty()) out << " m=" << regions->front().ratio;
  }
  for (const char* key : {"coupling", "schur", "method", "recovery"}) {
    if (c.options.contains(key)) out << " " << c.options[key].get<std::string>();
  }
  return out.str();
}

}  // namespace

std::vector<BenchmarkConfiguration> readConfigurations(const std::string& path, const Scene& scene,
                                                       const Simulation& baseline) {
  std::ifstream in(path);
  if (!in) throw Error(path + ": cannot open the configuration file");
  nlohmann::json json;
  try {
    json = nlohmann::json::parse(in, nullptr, true, true);
  } catch (const nlohmann::json::parse_error& error) {
    throw ParseError(path, 0, std::string("invalid JSON: ") + error.what());
  }
  if (!json.is_object() || !json.contains("configurations") || !json["configurations"].is_array()) {
    throw ValidationError(path + ": expected {\"configurations\": [...]}");
  }
  std::vector<BenchmarkConfiguration> out;
  const nlohmann::json& list = json["configurations"];
  for (std::size_t i = 0; i < list.size(); ++i) {
    const std::string where = path + ": configurations[" + std::to_string(i) + "]";
    const nlohmann::json& item = list[i];
    if (!item.is_object()) throw ValidationError(where + ": expected an object");
    BenchmarkConfiguration c;
    for (const auto& [key, value] : item.items()) {
      if (key == "label") {
        c.label = value.get<std::string>();
      } else if (key == "integrator") {
        c.integrator = value.get<std::string>();
      } else if (key == "stepsPerFrame") {
        c.stepsPerFrame = value.get<int>();
      } else if (key == "timestep") {
        c.timestep = value.get<double>();
      } else if (key == "options") {
        c.options = value;
      } else if (key == "plot") {
        c.plotTrajectory = value.get<bool>();
      } else if (key != "ratio") {
        throw ValidationError(
            where + "." + key +
            ": unknown key (known: label, integrator, stepsPerFrame, timestep, ratio, options, plot)");
      }
    }
    if (c.stepsPerFrame <= 0 && !(c.timestep > 0.0)) {
      throw ValidationError(where + ": give stepsPerFrame (>= 1) or timestep (> 0)");
    }
    completeOptions(c, scene);
    if (item.contains("ratio")) setRatio(c.options, item["ratio"].get<int>(), where + ".ratio", scene, baseline);
    if (c.label.empty()) c.label = defaultLabel(c, scene, baseline);
    out.push_back(std::move(c));
  }
  return out;
}

BenchmarkConfiguration parseConfigurationSpec(const std::string& spec, const Scene& scene, const Simulation& baseline) {
  std::vector<std::string> parts;
  std::stringstream stream(spec);
  for (std::string part; std::getline(stream, part, ':');) parts.push_back(part);
  if (parts.empty() || parts[0].empty())
    throw ValidationError("--config \"" + spec + "\": expected NAME[:key=value]...");
  BenchmarkConfiguration c;
  c.integrator = parts[0];
  c.plotTrajectory = true;
  std::optional<int> ratio;
  for (std::size_t k = 1; k < parts.size(); ++k) {
    const std::size_t eq = parts[k].find('=');
    if (eq == std::string::npos)
      throw ValidationError("--config \"" + spec + "\": \"" + parts[k] + "\" is not key=value");
    const std::string key = parts[k].substr(0, eq), value = parts[k].substr(eq + 1);
    try {
      if (key == "spf") {
        c.stepsPerFrame = std::stoi(value);
        if (c.stepsPerFrame < 1)
          throw ValidationError("--config \"" + spec + "\": spf must be >= 1 (got " + value + ")");
      } else if (key == "dt") {
        c.timestep = std::stod(value);
        if (!(c.timestep > 0.0)) throw ValidationError("--config \"" + spec + "\": dt must be > 0 (got " + value + ")");
      } else if (key == "ratio") {
        ratio = std::stoi(value);
      } else if (key == "coupling" || key == "schur" || key == "method" || key == "recovery" || key == "solver") {
        c.options[key] = value;
      } else if (key == "label") {
        c.label = value;
      } else {
        throw ValidationError("--config \"" + spec + "\": unknown key \"" + key +
                              "\" (known: spf, dt, ratio, coupling, schur, method, recovery, solver, label)");
      }
    } catch (const std::logic_error&) {
      throw ValidationError("--config \"" + spec + "\": bad number in \"" + parts[k] + "\"");
    }
  }
  if (c.stepsPerFrame <= 0 && !(c.timestep > 0.0)) {
    if (scene.timing.timestep > 0.0) {
      c.timestep = scene.timing.timestep;
    } else {
      throw ValidationError("--config \"" + spec + "\": give spf=N or dt=H");
    }
  }
  completeOptions(c, scene);
  // Any given ratio goes to the regions, so that the scene check rejects one out of range.
  if (ratio) setRatio(c.options, *ratio, "--config \"" + spec + "\".ratio", scene, baseline);
  if (c.label.empty()) c.label = defaultLabel(c, scene, baseline);
  return c;
}

std::vector<BenchmarkConfiguration> defaultConfigurations(const Scene& scene, const Simulation& baseline) {
  const double frame = scene.timing.frameInterval;
  // Steps per frame of the scene's own (large) timestep, at least 1.
  const int sceneSteps = std::max(1, static_cast<int>(std::lround(frame / scene.timing.timestep)));
  const std::optional<std::vector<AsyncRegion>> sceneRegions =
      isMultirate(scene.integrator.name) ? explicitRegions(scene.integrator.options, scene, baseline) : std::nullopt;
  const bool explicitRegions = sceneRegions.has_value();
  std::vector<BenchmarkConfiguration> out;
  auto add = [&](const std::string& integrator, int spf, int ratio, nlohmann::json options, bool plot) {
    BenchmarkConfiguration c;
    c.integrator = integrator;
    c.stepsPerFrame = spf;
    c.options = std::move(options);
    c.plotTrajectory = plot;
    completeOptions(c, scene);
    if (ratio > 0 && explicitRegions) setRatio(c.options, ratio, "default configuration", scene, baseline);
    c.label = defaultLabel(c, scene, baseline);
    out.push_back(std::move(c));
  };
  // The scene's own ratio; without explicit regions the middle of the ratios below.
  const int sceneRatio = explicitRegions ? largestRatio(*sceneRegions) : 8;
  for (const int spf : {1, 2, 4, 8, 16, 32, 64}) {
    add("backward-euler", spf, 0, nlohmann::json::object(), spf == sceneSteps || spf == sceneSteps * sceneRatio);
  }
  for (const int spf : {sceneSteps, 4 * sceneSteps}) add("trapezoidal", spf, 0, nlohmann::json::object(), false);
  // Central differences at the largest step below the stable limit (rigorous element bound).
  const double omega = estimateMaxFrequency(*baseline.mesh, scene.mass);
  const int explicitSteps = static_cast<int>(std::ceil(frame / (0.95 * stableTimestepFromFrequency(omega))));
  // Skipped when it would dominate the run time (add it with --config central-differences:spf=N).
  if (static_cast<long long>(explicitSteps) * scene.timing.frameCount <= 100000) {
    add("central-differences", explicitSteps, 0, nlohmann::json::object(), false);
  }
  if (explicitRegions) {
    for (const int ratio : {2, 4, 8, 16, 32})
      add("async", sceneSteps, ratio, nlohmann::json::object(), ratio == sceneRatio);
    for (const int spf : {std::max(1, sceneSteps / 2), 2 * sceneSteps}) {
      if (spf != sceneSteps) add("async", spf, sceneRatio, nlohmann::json::object(), false);
    }
    for (const int ratio : {2, 4, 8, 16, 32})
      add("async", sceneSteps, ratio, {{"coupling", "paper"}}, ratio == sceneRatio);
    add("async", sceneSteps, sceneRatio, {{"schur", "symmetric"}}, false);
    add("async", sceneSteps, sceneRatio, {{"schur", "lu"}}, false);
    add("async", sceneSteps, sceneRatio, {{"method", "naive"}}, false);
    for (const int ratio : {4, 8, 16}) {
      add("multirate-uncoupled", sceneSteps, ratio, nlohmann::json::object(), ratio == sceneRatio);
    }
    // Explicit in the outer layer's elastic forces: small ratios are refused (reported as
    // failing before the first frame, with the largest stable substep).
    for (const int ratio : {8, 32, 150}) {
      add("schroeder2011", sceneSteps, ratio, nlohmann::json::object(), ratio == sceneRatio);
    }
  } else {
    add("async", sceneSteps, 0, nlohmann::json::object(), true);
    add("multirate-uncoupled", sceneSteps, 0, nlohmann::json::object(), true);
    add("schroeder2011", sceneSteps, 0, nlohmann::json::object(), true);
  }
  return out;
}

std::string machineDescription() {
  std::string model = "unknown CPU";
  std::ifstream cpuinfo("/proc/cpuinfo");
  for (std::string line; std::getline(cpuinfo, line);) {
    if (line.rfind("model name", 0) == 0) {
      const std::size_t colon = line.find(':');
      if (colon != std::string::npos) model = line.substr(colon + 2);
      break;
    }
  }
  std::string load = "unknown";
  std::ifstream loadavg("/proc/loadavg");
  if (loadavg) {
    std::string a, b, c;
    loadavg >> a >> b >> c;
    load = a + " " + b + " " + c;
  }
  std::ostringstream out;
  out << "nproc " << std::thread::hardware_concurrency() << ", " << model << ", load average " << load;
  return out.str();
}

}  // namespace asyncfem::bench
