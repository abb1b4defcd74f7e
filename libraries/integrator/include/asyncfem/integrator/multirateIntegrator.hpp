// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/integrator/integrator.hpp>
#include <vector>

namespace asyncfem {

/// The region queries of an integrator whose fast regions take smaller steps than the
/// rest (the asynchronous and the uncoupled multirate integrators), which drivers use to
/// describe it (summaries, the region of a failing vertex, tinted frames). An interface:
/// such an integrator derives from Integrator and from this, and returns itself from
/// Integrator::multirate().
class MultirateIntegrator {
 public:
  virtual ~MultirateIntegrator() = default;

  /// The fast regions, in region order.
  virtual std::vector<RegionSummary> regionSummaries() const = 0;
  /// The index (into regionSummaries()) of the fast region holding vertex, or -1 when it
  /// lies in the large-step region L (or is out of range).
  virtual int regionOfVertex(int vertex) const = 0;
};

/// integrator's fast regions, or none for a single-rate integrator.
inline std::vector<RegionSummary> regionSummaries(const Integrator& integrator) {
  const MultirateIntegrator* multirate = integrator.multirate();
  return multirate ? multirate->regionSummaries() : std::vector<RegionSummary>{};
}

/// The fast region holding vertex, or -1 (L, or a single-rate integrator).
inline int regionOfVertex(const Integrator& integrator, int vertex) {
  const MultirateIntegrator* multirate = integrator.multirate();
  return multirate ? multirate->regionOfVertex(vertex) : -1;
}

}  // namespace asyncfem
