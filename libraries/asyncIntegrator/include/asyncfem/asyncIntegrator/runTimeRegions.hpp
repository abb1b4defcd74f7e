// SPDX-License-Identifier: BSD-3-Clause
// Fast regions chosen at run time: where contact is, where the large step's local error is,
// or when the user's schedule says.
#pragma once

#include <Eigen/Core>
#include <asyncfem/asyncIntegrator/loadsPolicy.hpp>
#include <asyncfem/asyncIntegrator/regionPartition.hpp>
#include <asyncfem/dynamics/dynamicSystem.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace asyncfem {

/// A fast region the user schedules: `vertices` at ratio m from `start` (inclusive) to
/// `end` (exclusive), in seconds.
struct ScheduledRegion {
  std::string name;
  double start = 0.0;
  double end = std::numeric_limits<double>::infinity();
  std::vector<int> vertices;
  int ratio = 1;
};

/// The policies of run-time regions and their hysteresis (docs/asynchronous-integrator.md,
/// "Run-time regions"). Policies combine: the regions wanted at a large-step boundary are
/// the contact region and every active scheduled region, merged where they touch (an
/// element with vertices in both) at the larger ratio, or nested (RunTimeRegionOptions::nest).
struct RunTimeRegionOptions {
  /// Contact policy: the vertices in contact or within contactMargin (a length) of an
  /// obstacle, at the step's start state or at the state predicted contactLookahead large
  /// steps ahead (u + k hL v), grown by contactRings element rings, at ratio contactRatio.
  /// A new contact region is grown by contactSlack rings more than that, so that a
  /// spreading patch stays inside it for a while instead of forcing a set-up per step.
  bool contact = false;
  int contactRatio = 8;
  double contactMargin = 0.0;
  double contactLookahead = 1.0;
  int contactRings = 1;
  int contactSlack = 1;
  /// Indicator policy: the local error of the large step, estimated per vertex from the
  /// last three large-step velocities as e_v = |v_k - 2 v_{k-1} + v_{k-2}| / 2 (the
  /// velocity error of one backward Euler step, (hL^2 / 2) dv/dt^2 in differences; Eq. R1),
  /// against indicatorTolerance times the body's RMS vertex speed. A vertex above it wants
  /// ratio e_v / (tolerance * speed) (a step's error falls as 1/m with m substeps), rounded
  /// up to a power of two and at most indicatorRatio; the marked vertices, grown by
  /// indicatorRings rings, form one region per connected component at the largest ratio
  /// its vertices want.
  bool indicator = false;
  double indicatorTolerance = 0.05;
  int indicatorRatio = 16;
  int indicatorRings = 1;
  /// Schedule policy.
  std::vector<ScheduledRegion> schedule;
  /// Loads policy (LoadsPolicy): a part that a load (a pull window that opens or closes, an
  /// impulse) reaches within the next large step is fast from that step: the given
  /// loadsParts holding a reached vertex at their own ratios, else the reached vertices grown
  /// by loadsRings at loadsRatio. It is released once the energy of its motion relative to
  /// the rigid motion of its neighbourhood (the part grown by loadsNeighbourhood rings) has
  /// stayed at or below loadsRelease times its peak since its last load change for minDwell
  /// large steps. Needs the body's external force (AsyncBackwardEuler passes it).
  bool loads = false;
  int loadsRatio = 8;
  int loadsRings = 1;
  std::vector<AsyncRegion> loadsParts;
  double loadsRelease = 0.01;
  int loadsNeighbourhood = 2;
  /// Hysteresis. A contact region that no longer covers what the policy needs is replaced
  /// at once, grown by contactSlack rings more than needed (so small moves stay inside it); one that
  /// covers it is kept for at least minDwell large steps, then replaced by a smaller one
  /// when it holds more than shrinkFactor times the vertices needed (or none is needed).
  /// The loads policy releases a part after minDwell quiet large steps.
  int minDwell = 8;
  double shrinkFactor = 2.0;
  /// Regions that touch keep their own ratios where those divide one another across every
  /// shared element (a nested partition, which AsyncBackwardEuler runs with its hierarchy
  /// solve); a vertex claimed by several regions goes to the fastest. false (default): every
  /// touching region is merged into one at the larger ratio (the two-level solve).
  bool nest = false;
  /// Set-ups kept for reuse: with linear forces a partition that comes back (the same
  /// contact patch at the next bounce, the end of a scheduled window) costs no rebuild.
  int cacheSize = 4;
};

/// One change of partition at a large-step boundary.
struct RepartitionRecord {
  double time = 0.0;      ///< seconds
  long long step = 0;     ///< large steps taken before it
  std::string reason;     ///< which policy asked and why
  int regions = 0;        ///< fast regions after it
  int fastVertices = 0;   ///< vertices in fast regions after it
  int interfaceDofs = 0;  ///< sum_i |I_i| after it
  int movedVertices = 0;  ///< vertices that changed region
  double seconds = 0.0;   ///< set-up time it cost (0 when reused)
  bool reused = false;    ///< taken from the set-up cache
};

/// Decides, at each large-step boundary, which fast regions a run needs.
class RunTimeRegionPolicy {
 public:
  /// Throws asyncfem::ValidationError for a ratio < 1, a negative margin, lookahead or
  /// ring count, minDwell < 0, shrinkFactor < 1, a schedule window with end <= start or
  /// vertices out of range, or contact requested for a system without obstacles
  /// (checked by the integrator).
  RunTimeRegionPolicy(const TetMesh& mesh, const FreeDofs& freeDofs, RunTimeRegionOptions options);

  /// The regions wanted now (time t, start state u, v, large step hL), merged and with
  /// vertices that have no free DOF left out. Empty: no fast region.
  std::vector<AsyncRegion> wanted(double time, double largeStep, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                                  const ObstacleProximity& proximity) const;
  /// Given the regions in use (kept for stepsKept large steps), the new regions to set up,
  /// or nothing to keep them; reason says why.
  std::optional<std::vector<AsyncRegion>> decide(double time, double largeStep, const Eigen::VectorXd& u,
                                                 const Eigen::VectorXd& v, const ObstacleProximity& proximity,
                                                 const std::vector<AsyncRegion>& current, long long stepsKept,
                                                 std::string& reason);

  /// Whether `regions` give every vertex the policy needs now at least the ratio it
  /// wants, and hold at most shrinkFactor times the vertices it would choose: a set-up
  /// that can serve the next steps in place of `proposal`. On the vertices of the
  /// schedule's windows, open or closed, the ratio must be exactly the one the policy
  /// gives them now (windows open and close exactly).
  bool canServe(const std::vector<AsyncRegion>& regions, const std::vector<AsyncRegion>& proposal, double time,
                double largeStep, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                const ObstacleProximity& proximity) const;

  const RunTimeRegionOptions& options() const { return options_; }

  /// The body's external force, for the loads policy (DynamicSystem::externalForce and
  /// externalForceChanges).
  void setExternalForce(ExternalForceFunction force, ExternalForceChanges changes);
  /// The loads policy's switches so far (empty without it).
  const std::vector<LoadsSwitch>& loadsSwitches() const;

 private:
  std::vector<char> contactVertices(double largeStep, const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                                    const ObstacleProximity& proximity, int rings) const;
  /// Ratio every vertex wants by the indicator (0: none), grown by indicatorRings + extra.
  std::vector<int> indicatorRatios(int extraRings) const;
  /// Takes the velocity at a new large-step boundary into the indicator's history.
  void recordVelocity(double time, const Eigen::VectorXd& v);
  std::vector<AsyncRegion> assemble(double time, const std::vector<char>& contact,
                                    const std::vector<int>& indicated) const;
  std::vector<int> activeWindows(double time) const;

  const TetMesh* mesh_;
  std::vector<char> hasFreeDof_;
  RunTimeRegionOptions options_;
  std::vector<int> lastWindows_;
  bool started_ = false;
  std::optional<LoadsPolicy> loads_;
  // The indicator's history: the velocities at the last three large-step boundaries.
  std::vector<Eigen::VectorXd> velocities_;
  double lastRecorded_ = -std::numeric_limits<double>::infinity();
};

/// Summary lines for a run's re-partitions: the count, how many came from the cache, the
/// set-up time they cost, then one line each (the first and last ten when there are more).
void appendRepartitionLines(const std::vector<RepartitionRecord>& records, std::vector<std::string>& lines);

}  // namespace asyncfem
