// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <asyncfem/modalAnalysis/lowestModes.hpp>
#include <iosfwd>
#include <string>
#include <vector>

namespace asyncfem {

/// The criteria of docs/asynchronous-integrator.md ("Which modes can async keep?"), from
/// the design note's "Where asynchronous stepping can win". A mode is worth integrating
/// asynchronously only if it lives in S, is visible at frame rate, is damped away by
/// backward Euler at hL, and is resolved at hS.
namespace modalCriteria {
/// Lives in S: share of modal mass phi_S^T M^{SS} phi_S >= 0.95. Below it, the motion of
/// the mode is carried by L as well, and L's part is integrated at hL whatever S does, so
/// substepping S cannot keep the mode.
inline constexpr double minFastShare = 0.95;
/// Visible: omega below the frame Nyquist frequency pi * frameRate (rad/s). Faster modes
/// alias or vanish between frames, so keeping them buys nothing a viewer sees.
inline constexpr double nyquistPerFrameRate = 3.141592653589793;
/// Damped by backward Euler at hL: omega hL >= 0.5. BE multiplies a mode's amplitude by
/// (1 + (omega h)^2)^(-1/2) per step, that is (1 + (omega h)^2)^(-pi / (omega h)) per period:
/// at omega h = 0.5 only 25% survives one period, at 0.1 still 73%. Below 0.5 single-rate
/// at hL keeps the mode well enough. (The design note's upper end, omega hL about 3, follows
/// from visibility and from resolvedOmegaSubstep with ratios up to about 30; both are
/// checked directly.)
inline constexpr double minDampedOmegaLargeStep = 0.5;
/// Resolved at hS: omega hS <= 0.1 (73% of the amplitude kept per period, see above; the
/// design note's 0.05 keeps 85%).
inline constexpr double maxResolvedOmegaSubstep = 0.1;
}  // namespace modalCriteria

/// A fast region as the modal report sees it: its vertices and ratio m (hS = hL / m).
/// (The same fields as asyncIntegrator's AsyncRegion, which sits above this library.)
struct ModalRegion {
  std::string name;
  std::vector<int> vertices;  ///< 0-based vertex ids
  int ratio = 1;
};

/// One mode in a region report.
struct ModeInRegions {
  double omega = 0.0;                ///< rad/s
  double hertz = 0.0;                ///< omega / (2 pi)
  double omegaLargeStep = 0.0;       ///< omega hL
  std::vector<double> omegaSubstep;  ///< omega hS_i per region
  std::vector<double> regionShare;   ///< phi_{S_i}^T M^{S_i S_i} phi_{S_i} per region, in [0, 1]
  double fastShare = 0.0;            ///< share of S = union of the regions (sum of regionShare)
  bool visible = false;              ///< omega < pi frameRate
  bool livesInFastRegions = false;   ///< visible and fastShare >= minFastShare
  bool keepable = false;             ///< lives in S, omega hL >= 0.5, omega hS <= 0.1 in its main region
};

/// What the report concludes.
enum class ModalVerdict {
  asyncKeepsModes,      ///< some mode passes every criterion
  noVisibleModeInFast,  ///< no visible mode lives in S (or there is no S)
  resolvedAtLargeStep,  ///< modes live in S but omega hL < 0.5: single-rate keeps them
  unresolvedAtSubstep,  ///< modes live in S and are damped at hL, but omega hS > 0.1: raise m
};

/// Per-mode report for a partition.
struct RegionModeReport {
  double largeTimestep = 0.0;  ///< hL (s)
  double frameRate = 0.0;      ///< frames per second
  double nyquistOmega = 0.0;   ///< pi frameRate (rad/s)
  std::vector<std::string> regionNames;
  std::vector<int> ratios;
  std::vector<ModeInRegions> modes;  ///< ascending frequency
  /// True when the highest computed mode is still below the Nyquist frequency: visible
  /// modes above it were not examined.
  bool visibleModesTruncated = false;
  ModalVerdict verdict = ModalVerdict::noVisibleModeInFast;
  std::vector<int> keptModes;  ///< 0-based indices into modes of the keepable ones
  /// One line: "async can keep these modes: ...", "no mode below the frame Nyquist
  /// frequency lives in S: single-rate at hL costs less for the same result", ...
  std::string verdictText() const;
};

/// Shares, omega h and the verdict for every mode of result in the given regions.
/// mass: the full 3n x 3n M the modes are M-orthonormal in. Regions never share an element
/// (RegionPartition's rule), so M^{S_i S_j} = 0 for i != j and the shares of the regions add
/// up to the share of their union. Throws asyncfem::ValidationError for hL <= 0, frameRate
/// <= 0, a ratio < 1, a vertex out of range or a size mismatch.
RegionModeReport analyseRegionModes(const ModalResult& result, const Eigen::SparseMatrix<double>& mass,
                                    const std::vector<ModalRegion>& regions, double largeTimestep, double frameRate);

/// Prints the table (mode, Hz, rad/s, omega hL, per region omega hS and share, S share,
/// flags) and the verdict line to out.
void printRegionModeReport(std::ostream& out, const RegionModeReport& report);

}  // namespace asyncfem
