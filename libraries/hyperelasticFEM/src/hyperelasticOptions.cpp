// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/hyperelasticFEM/hyperelasticOptions.hpp>
#include <cctype>
#include <cmath>
#include <sstream>

namespace asyncfem {

HyperelasticMaterialKind parseHyperelasticMaterialKind(std::string_view name) {
  std::string lower(name);
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (lower == "stvk") return HyperelasticMaterialKind::stvk;
  if (lower == "neo-hookean" || lower == "neohookean") return HyperelasticMaterialKind::neoHookean;
  if (lower == "mooney-rivlin" || lower == "mooneyrivlin") return HyperelasticMaterialKind::mooneyRivlin;
  throw ValidationError("unknown hyperelastic material '" + std::string(name) +
                        "' (expected stvk, neo-hookean or mooney-rivlin)");
}

std::string toString(HyperelasticMaterialKind kind) {
  switch (kind) {
    case HyperelasticMaterialKind::stvk:
      return "stvk";
    case HyperelasticMaterialKind::neoHookean:
      return "neo-hookean";
    case HyperelasticMaterialKind::mooneyRivlin:
      return "mooney-rivlin";
  }
  return "unknown";
}

LameParameters vegaLameParameters(double youngsModulus, double poissonRatio) {
  // Vega's ENuMaterial: getLambda() = nu E / ((1 + nu)(1 - 2 nu)), getMu() = E / (2 (1 + nu)).
  return {(poissonRatio * youngsModulus) / ((1.0 + poissonRatio) * (1.0 - (2.0 * poissonRatio))),
          youngsModulus / (2.0 * (1.0 + poissonRatio))};
}

SmallStrainModuli mooneyRivlinSmallStrainModuli(const MooneyRivlinParameters& parameters) {
  const double shear = 2.0 * (parameters.mu10 + parameters.mu01);
  const double bulk = 2.0 * parameters.v1;
  if (!std::isfinite(parameters.mu01) || !std::isfinite(parameters.mu10) || !std::isfinite(parameters.v1) ||
      !(shear > 0.0) || !(bulk > 0.0)) {
    std::ostringstream message;
    message << "Mooney-Rivlin parameters mu01 = " << parameters.mu01 << ", mu10 = " << parameters.mu10
            << ", v1 = " << parameters.v1
            << " are not a stable material: need finite values with mu10 + mu01 > 0 and v1 > 0";
    throw ValidationError(message.str());
  }
  return {parameters.equivalentYoungsModulus(), parameters.equivalentPoissonRatio()};
}

}  // namespace asyncfem
