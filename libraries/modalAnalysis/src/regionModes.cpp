// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/modalAnalysis/regionModes.hpp>
#include <cmath>
#include <cstdio>
#include <ostream>
#include <sstream>

namespace asyncfem {

namespace {

// "3 (1.52 Hz), 4 (2.01 Hz)": 1-based mode numbers with their frequencies.
std::string modeList(const RegionModeReport& report, const std::vector<int>& indices) {
  std::ostringstream out;
  for (std::size_t k = 0; k < indices.size(); ++k) {
    const ModeInRegions& mode = report.modes[static_cast<std::size_t>(indices[k])];
    char buffer[96];
    std::snprintf(buffer, sizeof buffer, "%s%d (%.3g Hz, omega*hL %.2f)", k ? ", " : "", indices[k] + 1, mode.hertz,
                  mode.omegaLargeStep);
    out << buffer;
  }
  return out.str();
}

}  // namespace

std::string RegionModeReport::verdictText() const {
  std::vector<int> inFast;
  for (std::size_t j = 0; j < modes.size(); ++j)
    if (modes[j].livesInFastRegions) inFast.push_back(static_cast<int>(j));
  switch (verdict) {
    case ModalVerdict::asyncKeepsModes:
      return "async can keep these modes: " + modeList(*this, keptModes);
    case ModalVerdict::resolvedAtLargeStep:
      return "modes " + modeList(*this, inFast) +
             " live in S but are already resolved at hL (omega*hL < 0.5): single-rate at hL already keeps them";
    case ModalVerdict::unresolvedAtSubstep:
      return "modes " + modeList(*this, inFast) +
             " live in S and are damped at hL, but not resolved at hS (omega*hS > 0.1): raise the ratio m";
    case ModalVerdict::noVisibleModeInFast:
      break;
  }
  return "no mode below the frame Nyquist frequency lives in S: single-rate at hL costs less for the same result";
}

namespace {

// Throws ValidationError unless hL and the frame rate are positive and the modes match M.
void checkModalInputs(const ModalResult& result, const Eigen::SparseMatrix<double>& mass, double largeTimestep,
                      double frameRate) {
  if (!(largeTimestep > 0.0) || !std::isfinite(largeTimestep)) {
    throw ValidationError("modal report: the large timestep hL must be positive");
  }
  if (!(frameRate > 0.0) || !std::isfinite(frameRate)) {
    throw ValidationError("modal report: the frame rate must be positive");
  }
  const Eigen::Index numDofs = mass.rows();
  if (mass.cols() != numDofs || result.modes.rows() != numDofs || result.frequencies.size() != result.modes.cols()) {
    throw ValidationError("modal report: the modes (" + std::to_string(result.modes.rows()) +
                          " DOFs) do not match M (" + std::to_string(mass.rows()) + "x" + std::to_string(mass.cols()) +
                          ")");
  }
}

// Share of every mode in the region: the modes masked to its DOFs, phi_S^T M phi_S (the
// masked vector has zeros outside S, so this is phi_S^T M^{SS} phi_S). Throws
// ValidationError for a ratio below 1 or a vertex outside the mesh.
Eigen::VectorXd regionShares(const ModalRegion& region, const ModalResult& result,
                             const Eigen::SparseMatrix<double>& mass) {
  const Eigen::Index numDofs = mass.rows();
  if (region.ratio < 1) {
    throw ValidationError("modal report: region '" + region.name + "' has ratio " + std::to_string(region.ratio) +
                          " (must be >= 1)");
  }
  Eigen::VectorXd mask = Eigen::VectorXd::Zero(numDofs);
  for (int v : region.vertices) {
    if (v < 0 || 3 * static_cast<Eigen::Index>(v) + 2 >= numDofs) {
      throw ValidationError("modal report: region '" + region.name + "' names vertex " + std::to_string(v) +
                            ", outside [0, " + std::to_string(numDofs / 3) + ")");
    }
    mask.segment<3>(3 * static_cast<Eigen::Index>(v)).setOnes();
  }
  const Eigen::MatrixXd masked = mask.asDiagonal() * result.modes;
  const Eigen::MatrixXd massTimesMasked = mass * masked;
  return masked.cwiseProduct(massTimesMasked).colwise().sum().transpose();
}

// Mode j against the regions: frequencies, omega h per region, shares, and whether it
// is visible at the frame rate, lives in the fast regions and can be kept by async.
ModeInRegions classifyMode(std::size_t j, const ModalResult& result, const std::vector<ModalRegion>& regions,
                           const std::vector<Eigen::VectorXd>& shares, double largeTimestep, double nyquistOmega) {
  ModeInRegions mode;
  mode.omega = result.frequencies[static_cast<Eigen::Index>(j)];
  mode.hertz = mode.omega / (2.0 * modalCriteria::nyquistPerFrameRate);
  mode.omegaLargeStep = mode.omega * largeTimestep;
  std::size_t mainRegion = 0;
  for (std::size_t i = 0; i < regions.size(); ++i) {
    mode.omegaSubstep.push_back(mode.omegaLargeStep / regions[i].ratio);
    mode.regionShare.push_back(shares[i][static_cast<Eigen::Index>(j)]);
    mode.fastShare += mode.regionShare.back();
    if (mode.regionShare[i] > mode.regionShare[mainRegion]) mainRegion = i;
  }
  mode.visible = mode.omega < nyquistOmega;
  mode.livesInFastRegions = mode.visible && mode.fastShare >= modalCriteria::minFastShare;
  mode.keepable = mode.livesInFastRegions && mode.omegaLargeStep >= modalCriteria::minDampedOmegaLargeStep &&
                  mode.omegaSubstep[mainRegion] <= modalCriteria::maxResolvedOmegaSubstep;
  return mode;
}

// The report's verdict from its classified modes and kept modes.
ModalVerdict regionModeVerdict(const RegionModeReport& report) {
  const bool anyInFast = std::any_of(report.modes.begin(), report.modes.end(),
                                     [](const ModeInRegions& m) { return m.livesInFastRegions; });
  const bool allResolvedAtLarge = std::all_of(report.modes.begin(), report.modes.end(), [](const ModeInRegions& m) {
    return !m.livesInFastRegions || m.omegaLargeStep < modalCriteria::minDampedOmegaLargeStep;
  });
  if (!report.keptModes.empty()) return ModalVerdict::asyncKeepsModes;
  if (!anyInFast) return ModalVerdict::noVisibleModeInFast;
  if (allResolvedAtLarge) return ModalVerdict::resolvedAtLargeStep;
  return ModalVerdict::unresolvedAtSubstep;
}

}  // namespace

RegionModeReport analyseRegionModes(const ModalResult& result, const Eigen::SparseMatrix<double>& mass,
                                    const std::vector<ModalRegion>& regions, double largeTimestep, double frameRate) {
  checkModalInputs(result, mass, largeTimestep, frameRate);
  RegionModeReport report;
  report.largeTimestep = largeTimestep;
  report.frameRate = frameRate;
  report.nyquistOmega = modalCriteria::nyquistPerFrameRate * frameRate;
  std::vector<Eigen::VectorXd> shares;
  for (const ModalRegion& region : regions) {
    shares.push_back(regionShares(region, result, mass));
    report.regionNames.push_back(region.name);
    report.ratios.push_back(region.ratio);
  }
  const auto numModes = static_cast<std::size_t>(result.modes.cols());
  for (std::size_t j = 0; j < numModes; ++j) {
    ModeInRegions mode = classifyMode(j, result, regions, shares, largeTimestep, report.nyquistOmega);
    if (mode.keepable) report.keptModes.push_back(static_cast<int>(j));
    report.modes.push_back(std::move(mode));
  }
  report.visibleModesTruncated = !report.modes.empty() && report.modes.back().visible;
  report.verdict = regionModeVerdict(report);
  return report;
}

void printRegionModeReport(std::ostream& out, const RegionModeReport& report) {
  char buffer[128];
  std::snprintf(buffer, sizeof buffer, "hL = %.6g s, frame rate %.6g /s: Nyquist omega = %.4g rad/s (%.4g Hz)\n",
                report.largeTimestep, report.frameRate, report.nyquistOmega, report.frameRate / 2.0);
  out << buffer;
  std::snprintf(buffer, sizeof buffer, "%4s %10s %11s %8s", "mode", "Hz", "rad/s", "w*hL");
  out << buffer;
  for (std::size_t i = 0; i < report.regionNames.size(); ++i) {
    const std::string name = report.regionNames[i] + "(m=" + std::to_string(report.ratios[i]) + ")";
    std::snprintf(buffer, sizeof buffer, " %18s %8s", ("w*hS " + name).c_str(), "share");
    out << buffer;
  }
  std::snprintf(buffer, sizeof buffer, " %8s  %s\n", "S share", "flags");
  out << buffer;
  for (std::size_t j = 0; j < report.modes.size(); ++j) {
    const ModeInRegions& mode = report.modes[j];
    std::snprintf(buffer, sizeof buffer, "%4zu %10.4g %11.5g %8.3f", j + 1, mode.hertz, mode.omega,
                  mode.omegaLargeStep);
    out << buffer;
    for (std::size_t i = 0; i < mode.regionShare.size(); ++i) {
      std::snprintf(buffer, sizeof buffer, " %18.4f %8.3f", mode.omegaSubstep[i], mode.regionShare[i]);
      out << buffer;
    }
    std::snprintf(buffer, sizeof buffer, " %8.3f  %s%s%s\n", mode.fastShare, mode.visible ? "visible" : "above-Nyquist",
                  mode.livesInFastRegions ? " in-S" : "", mode.keepable ? " keep" : "");
    out << buffer;
  }
  if (report.visibleModesTruncated) {
    out << "note: all " << report.modes.size()
        << " modes computed lie below the Nyquist frequency; ask for more modes to see every visible one\n";
  }
  out << report.verdictText() << "\n";
}

}  // namespace asyncfem
