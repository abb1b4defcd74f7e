// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <asyncfem/asyncIntegrator/regionPartition.hpp>
#include <asyncfem/modalAnalysis/regionModes.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <optional>
#include <vector>

namespace asyncfem {

/// Highest natural frequency (rad/s) of one linear tetrahedron on its own: omega_e^2 is the
/// largest eigenvalue of K_e v = lambda M_e v with the element's lumped mass (rho V / 4 on
/// every DOF). Computed in closed form, exactly (to rounding): from the eigenvalues g_i of
/// G = sum_a grad N_a grad N_a^T, omega_e^2 = 4 / rho times the largest eigenvalue of
/// 2 mu diag(g) + lambda sqrt(g) sqrt(g)^T (Lame constants lambda, mu): two 3x3 eigenvalue
/// problems instead of the 12x12 one (docs/asynchronous-integrator.md, "Proposed regions").
double elementMaxFrequency(const Eigen::Matrix<double, 3, 4>& restPositions, const Material& material);
/// The highest natural frequency of one trilinear hexahedron (vertices in hexahedron.hpp's order):
/// the largest eigenvalue of K_e v = lambda M_e v with hexLinearStiffness and hexLumpedMass
/// (rho int N_a dV on every DOF of vertex a), from the 24 x 24 symmetric eigenproblem of
/// M_e^{-1/2} K_e M_e^{-1/2}. Throws asyncfem::ValidationError as hexLinearStiffness for a
/// rest shape with det J <= 0 at a Gauss point.
double hexahedronMaxFrequency(const Eigen::Matrix<double, 3, 8>& restPositions, const Material& material);

/// elementMaxFrequency() or hexahedronMaxFrequency() of every element. By the element
/// eigenvalue inequality, max_e omega_e bounds the assembled system's highest frequency
/// (lumped mass) from above, so it is a safe measure of how small a timestep an element
/// wants.
Eigen::VectorXd elementMaxFrequencies(const TetMesh& mesh);

struct RegionProposalOptions {
  double largeTimestep = 1e-2;  ///< hL (s)
  /// Target for omega * h in every region: an element with omega_e hL above it wants a
  /// fast region with ratio ceil(omega_e hL / target). <= 0: relative mode (below).
  double targetOmegaH = 0.0;
  /// Relative mode: target = relativeThreshold * median(omega_e) * hL. Implicit integrators
  /// run with omega_max h far above 1 (the highest element modes are invisible and damped
  /// away); what matters is that stiff or light parts are not resolved much worse than the
  /// bulk, so the default marks elements more than 3x "faster" than the median one.
  double relativeThreshold = 3.0;
  /// Rings of vertices added around each fast region (0: none). Growing moves the
  /// interface away from the stiff material and rounds its outline, which keeps the
  /// interface (the dense part of H^{LL*}) small relative to |S|.
  int growLayers = 1;
  int maxRatio = 256;
  /// Modal check (docs/asynchronous-integrator.md, "Which modes can async keep?"), run by
  /// the overload of proposeRegions() that takes K and M: the regions are withdrawn when no
  /// visible mode (omega below pi * frameRate) among the lowest ones has a share of modal
  /// mass >= modalCriteria::minFastShare in them. Async with such regions keeps nothing
  /// that single-rate at hL loses, at m times the cost in S. Off by default here; the scene
  /// path ("regions": "auto") and the proposeRegions utility turn it on.
  bool modalCheck = false;
  /// The pre-check, run with the modal check before the cost check and instead of any
  /// eigensolve (docs/asynchronous-integrator.md, "Proposed regions"): when no element is
  /// fast by its material and size alone (elementSizeFrequency(), against the target the
  /// element criterion uses), the marked elements are fast by their shape only, which no
  /// visible mode of a part follows, and every region is withdrawn without a cost check or
  /// a modal solve (RegionProposalPath::precheck). false: the checks run as they did before it.
  bool precheck = true;
  double frameRate = 30.0;  ///< frames per second, for the visibility test
  /// Modes computed first; raised while the highest is still visible (to where a power law
  /// through the computed spectrum puts the Nyquist frequency, plus a fifth, at least
  /// doubled), up to maxModalCount. Every count uses the same factorization of K - sigma M
  /// (LowestModesSolver).
  int modalCount = 20;
  int maxModalCount = 80;
  /// Relative tolerance of the modal check's Ritz values (ModalOptions::tolerance). The
  /// check compares omega hL with 0.5 and shares with 0.95, so 1e-6 is ample and needs
  /// fewer restarts than lowestModes()'s 1e-10.
  double modalTolerance = 1e-6;
  /// The omega hS the modal check gives the modes a region keeps (visible, living mainly
  /// in it, damped at hL): its ratio becomes at least ceil(omega hL / modeOmegaSubstep).
  /// 0.05 is the design note's resolution (backward Euler keeps 85% of the amplitude per
  /// period); the check's own floor, modalCriteria::maxResolvedOmegaSubstep = 0.1, keeps 73%.
  double modeOmegaSubstep = 0.05;
  /// At most this many regions: beyond it the regions needing the smallest ratio (then the
  /// smallest) move to RegionProposal::cappedRegions and run at hL.
  int maxRegions = 4;
  /// Cost check (RegionProposalCost): the regions are withdrawn unless the estimated cost of an
  /// asynchronous large step is below costMargin times the cost of the single-rate steps
  /// that would meet the target everywhere (hL / max ratio) over the same time.
  bool costCheck = true;
  double costMargin = 1.0;
  /// Nonlinear (corotational) forces: both sides also refactor every step (the async
  /// rebuild: A^S, the Z columns, H^{LL*}).
  bool nonlinear = false;
};

/// The cost model of the proposal, in flops (the counts the benchmarks report: sparse
/// solves from factor sizes, dense interface work from interface sizes). Factor sizes and
/// factorization flops are CHOLMOD's own, from a symbolic analysis (METIS ordering) of each
/// block's pattern: the whole free system, every region's A^S, and A^L with each region's
/// dense interface block (H^{LL*}); a solve costs 4 flops per factor non-zero.
struct RegionProposalCost {
  bool evaluated = false;
  int freeDofs = 0;
  int largeDofs = 0;      ///< |L| once the regions are taken out
  int interfaceDofs = 0;  ///< sum_i |I_i|
  /// Single-rate steps per large step at the step the target needs everywhere: the
  /// largest ratio of the proposal (1 when nothing is proposed).
  int singleRateSubsteps = 1;
  double singleRateFlops = 0.0;       ///< per large step: singleRateSubsteps steps at hL / that
  double asyncFlops = 0.0;            ///< per large step, steady state (nonlinear: rebuild included)
  double singleRateSetupFlops = 0.0;  ///< before the first step (factorization)
  double asyncSetupFlops = 0.0;       ///< before the first step (A^S factors, Z, H^{LL*} factor)
  bool asyncCheaper = false;
  /// One line for a run summary: the numbers and what was decided.
  std::string decision;
  double ratio() const { return singleRateFlops > 0.0 ? asyncFlops / singleRateFlops : 0.0; }
};

/// The frequency an element would have with its material and size but the best shape: the
/// highest natural frequency (elementMaxFrequency()) of a regular tetrahedron of the
/// element's material whose edge is the element's RMS edge length. It is the element
/// frequency with the shape taken out: a slim or flat element has a much higher
/// elementMaxFrequency() than this, a small one or one of a fast material (stiff or light)
/// a higher value of this.
double elementSizeFrequency(const Eigen::Matrix<double, 3, 4>& restPositions, const Material& material);

/// Which step of proposeRegions() made the decision.
enum class RegionProposalPath {
  elementCriterion,  ///< nothing marked (every element meets the target), or regions kept with every check off
  precheck,          ///< the pre-check withdrew the marked regions: no cost check, no modal solve
  costCheck,         ///< the cost check withdrew the regions, or kept them with the modal check off
  modalCheck,        ///< the modal check (a modal solve) kept or withdrew the regions
};
const char* toString(RegionProposalPath path);

/// What the pre-check (RegionProposalOptions::precheck) measured.
struct RegionProposalPrecheck {
  bool evaluated = false;
  /// No element is fast by its material and size alone: every element's
  /// elementSizeFrequency() times hL is at most sizeTarget.
  bool shapeOnly = false;
  double sizeTarget = 0.0;  ///< omega*hL limit: the relative threshold times the median, or the absolute target
  double medianSizeFrequency = 0.0;    ///< median of elementSizeFrequency() over elements (rad/s)
  double maxSizeFrequencyRatio = 0.0;  ///< max over elements of elementSizeFrequency() / its median
  double waveSpeedSpread = 1.0;        ///< fastest material's regular-tet frequency / slowest's, over elements
  double sizeSpread = 1.0;             ///< largest RMS edge length / smallest
  int markedElements = 0;              ///< elements above the element criterion's target
  int sizeMarkedElements = 0;          ///< elements above sizeTarget by material and size
};

/// One proposed fast region with its statistics.
struct ProposedRegion {
  AsyncRegion region;
  double maxFrequency = 0.0;  ///< max omega_e over its elements (rad/s)
  int numElements = 0;        ///< elements with every vertex in the region
  int numInterfaceDofs = 0;   ///< |I| of the region once partitioned
  /// The element criterion's ratio when the modal check raised it (the modes living in the
  /// region needed more substeps); 0 when it was kept.
  int ratioFromElements = 0;
  /// When the modal check set the ratio: the mode that needed it (0-based index into
  /// RegionProposal::modalReport->modes, the fastest one the region keeps); else -1.
  int modeForRatio = -1;
};

struct RegionProposal {
  std::vector<ProposedRegion> regions;
  double largeRegionMaxFrequency = 0.0;  ///< max omega_e over elements touching no fast vertex
  double largeTimestep = 0.0;
  double targetOmegaH = 0.0;      ///< the target in effect (absolute, or from the relative mode)
  double modeOmegaSubstep = 0.0;  ///< options.modeOmegaSubstep (ratios from kept modes)
  /// Set when the modal check ran (there were regions to check): the report for the regions
  /// the frequency criterion proposed.
  std::optional<RegionModeReport> modalReport;
  /// Regions the frequency criterion proposed and the modal check withdrew (regions is then
  /// empty: the asynchronous integrator runs single-rate at hL).
  std::vector<ProposedRegion> withdrawnRegions;
  double modalSeconds = 0.0;  ///< time of the eigensolves of the modal check
  /// The modal check's solve: factorizations of K - sigma M (one, kept for every count) and
  /// back-substitutions with it (0 when it did not run).
  int modalFactorizations = 0;
  int modalSolves = 0;
  double modalFactorSeconds = 0.0;
  /// The pre-check's numbers, and the regions it withdrew (regions is then empty).
  RegionProposalPrecheck precheck;
  std::vector<ProposedRegion> precheckWithdrawnRegions;
  /// Which step decided.
  RegionProposalPath decidedBy = RegionProposalPath::elementCriterion;
  /// Wall time of proposeRegions(): the element frequencies, and the whole call (marking,
  /// partition, cost check, and the modal check when it ran; the K and M it is given are
  /// assembled by the caller and not counted).
  double frequencySeconds = 0.0;
  double decisionSeconds = 0.0;
  /// The cost check (options.costCheck) of the regions after the cap, and the regions it
  /// withdrew (regions is then empty: single-rate at hL).
  RegionProposalCost cost;
  std::vector<ProposedRegion> costWithdrawnRegions;
  /// Regions beyond options.maxRegions, dropped (they run at hL).
  std::vector<ProposedRegion> cappedRegions;
  /// The regions alone, ready for RegionPartition / AsyncBackwardEuler.
  std::vector<AsyncRegion> asyncRegions() const;
};

/// Proposes fast regions so that every region's omega * h stays under the target:
/// elements whose omega_e hL exceeds the target are marked, their vertices grown by
/// growLayers rings, enclosed L vertices (all neighbours fast) filled in, and each
/// connected component becomes one region (so regions never share an element: components
/// that would touch are one component) with ratio = ceil(max omega_e hL / target), capped
/// at maxRatio. Components without free DOFs are dropped. At most options.maxRegions are
/// kept (cappedRegions), then the cost check (RegionProposalCost) withdraws them all unless
/// async is estimated cheaper than single-rate at the step they would otherwise need. The
/// proposal is a valid partition for RegionPartition.
/// Ignores options.modalCheck (it needs K and M: use the overload below).
RegionProposal proposeRegions(const TetMesh& mesh, const FreeDofs& freeDofs, const RegionProposalOptions& options);

/// The cost model alone, for any regions (e.g. a scene's own): flops per large step of
/// async with these regions against single-rate at hL / (largest ratio).
RegionProposalCost estimateAsyncCost(const TetMesh& mesh, const FreeDofs& freeDofs,
                                     const std::vector<AsyncRegion>& regions, bool nonlinear = false,
                                     double costMargin = 1.0);

/// The same proposal, with the pre-check (options.precheck) before the cost check and the
/// modal check when options.modalCheck is set; the modal check runs when regions survived
/// the pre-check and the cost check: lowestModes() of stiffness and mass (full 3n x 3n,
/// e.g. vibrationMatrices()) and analyseRegionModes() of the proposed regions at
/// hL = options.largeTimestep. The ratio of each region is then taken from the modes it
/// keeps (visible, living mainly in it, damped at hL: omega hS <= options.modeOmegaSubstep,
/// at most maxRatio) where that is more than the element criterion's
/// (ProposedRegion::ratioFromElements keeps the old one, modeForRatio names the mode), and
/// the report and the cost check are redone for the new ratios. When the verdict is
/// ModalVerdict::noVisibleModeInFast the regions move to withdrawnRegions.
/// The mode counts are clamped to the free DOFs - 1. Throws ValidationError for frameRate <= 0,
/// modeOmegaSubstep <= 0 or counts out of order, and what lowestModes() throws.
RegionProposal proposeRegions(const TetMesh& mesh, const FreeDofs& freeDofs, const RegionProposalOptions& options,
                              const Eigen::SparseMatrix<double>& stiffness, const Eigen::SparseMatrix<double>& mass);

/// The same proposal with K and M assembled (vibrationMatrices(mesh, massType)) only when
/// the modal check runs, so that a decision the element criterion, the pre-check or the cost
/// check makes costs no assembly; decisionSeconds then counts the assembly when it ran.
/// What the scene path ("regions": "auto") runs.
RegionProposal proposeRegions(const TetMesh& mesh, const FreeDofs& freeDofs, const RegionProposalOptions& options,
                              MassType massType);

/// Why the region has its ratio, one phrase: the mode it keeps that needed it (frequency,
/// omega hL, omega hS against options.modeOmegaSubstep, and the element criterion's ratio),
/// or the element criterion (max omega_e hL against the target).
std::string ratioReason(const RegionProposal& proposal, const ProposedRegion& region);

/// One line for a run summary saying what the region proposal decided and why: the
/// regions kept (vertices, and why each has its ratio: ratioReason()), or that none was kept
/// and which check withdrew them (the modal verdict, the cost decision), or that every
/// element meets the target; then the time the decision took (decisionSeconds).
std::string regionProposalSummary(const RegionProposal& proposal);

/// The regions as the modal report takes them (name, vertices, ratio).
std::vector<ModalRegion> modalRegions(const std::vector<AsyncRegion>& regions);

}  // namespace asyncfem
