// SPDX-License-Identifier: BSD-3-Clause
// The loads policy of run-time regions: a part that a load reaches within the next large
// step is fast from that step, and released once its motion relative to its neighbourhood
// has died down (docs/asynchronous-integrator.md, "Run-time regions").
#pragma once

#include <Eigen/Core>
#include <asyncfem/asyncIntegrator/regionPartition.hpp>
#include <asyncfem/dynamics/dynamicSystem.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <limits>
#include <string>
#include <vector>

namespace asyncfem {

/// Vertex masses, lumped: every element gives rho V / 4 to each of its four vertices.
Eigen::VectorXd lumpedVertexMasses(const TetMesh& mesh);

/// The kinetic energy of the motion of `part` relative to the rigid motion of its
/// neighbourhood: with masses m_i, positions x_i = X_i + u_i and velocities v_i, the rigid
/// velocity field v_c + w x (x - c) is fitted to the velocities of `neighbourhood` by
/// mass-weighted least squares (c and v_c its centre of mass and mean velocity, w = I^{-1} L
/// from its inertia tensor and angular momentum about c; a degenerate I, e.g. collinear
/// vertices, is inverted on its range only), and the energy is
/// 1/2 sum_{i in part} m_i |v_i - v_c - w x (x_i - c)|^2. Zero when the part moves
/// rigidly with its neighbourhood (J for SI inputs).
double relativeMotionEnergy(const TetMesh& mesh, const Eigen::VectorXd& vertexMass, const std::vector<int>& part,
                            const std::vector<int>& neighbourhood, const Eigen::VectorXd& u, const Eigen::VectorXd& v);

/// The vertices (ascending) a load reaches in the large step (t0, t0 + hL]: those whose
/// external force at the fixed state (u, v) differs at one of the times t0 + r hL / ratio
/// (r = 1 .. ratio, the last exactly t0 + hL: the substep times of a region of that ratio)
/// from its value at `from` (t0, or a little before it at a run's first boundary, so that a
/// load from t = 0 counts). A pull window that opens or closes and an impulse count; gravity,
/// a load that stays on and penalty contact (the state is held fixed) do not. A load
/// shorter than hL / ratio that falls between those times reaches no vertex (no substep of
/// that ratio would see it either). `changes`, when set, is asked first: a force it says
/// is constant in (from, t0 + hL] is not evaluated at all.
std::vector<int> verticesReachedByLoads(const ExternalForceFunction& force, const ExternalForceChanges& changes,
                                        double from, double t0, double largeStep, int ratio, const Eigen::VectorXd& u,
                                        const Eigen::VectorXd& v);

/// The settings of the loads policy (RunTimeRegionOptions::loads*).
struct LoadsPolicySettings {
  int ratio = 8;                   ///< ratio of a part made of loaded vertices, and the probe's substeps
  int rings = 1;                   ///< element rings grown around loaded vertices that no given part holds
  std::vector<AsyncRegion> parts;  ///< candidate parts (vertex sets at their own ratios)
  double release = 0.01;           ///< release below this fraction of the part's peak relative energy ...
  int minDwell = 8;                ///< ... for this many consecutive large-step boundaries
  int neighbourhood = 2;           ///< rings around a part whose rigid motion its motion is measured against
};

/// One switch of the loads policy, as the summary explains it.
struct LoadsSwitch {
  double time = 0.0;  ///< the large-step boundary (s)
  std::string part;
  bool fast = false;        ///< true: switched fast; false: released
  int reachedVertices = 0;  ///< switched fast: its vertices a load reaches in the step ahead
  double energy = 0.0;      ///< released: relativeMotionEnergy() at the release (J)
  double peak = 0.0;        ///< released: its largest value since the part's last load change
  std::string text;         ///< the explanation (policy, part, time, energy)
};

/// The parts the loads policy holds fast. A load that reaches a vertex in the step ahead
/// (verticesReachedByLoads) makes every given part holding that vertex fast from that step;
/// reached vertices in no given part form parts of their own (grown by `rings`, one per
/// connected component, at `ratio`; a later load on the same vertices reuses it). A fast
/// part whose load changes no more is released once relativeMotionEnergy() over its
/// neighbourhood has stayed at or below `release` times its peak since its last load change
/// for `minDwell` consecutive large-step boundaries.
class LoadsPolicy {
 public:
  /// hasFreeDof: per vertex (loads on vertices without a free DOF are ignored). Throws
  /// asyncfem::ValidationError for ratio < 2, rings, neighbourhood or minDwell < 0, release
  /// outside [0, 1), a part's ratio < 2 or a vertex out of range.
  LoadsPolicy(const TetMesh& mesh, std::vector<char> hasFreeDof, LoadsPolicySettings settings);

  /// The body's external force, which the policy probes (DynamicSystem::externalForce and
  /// externalForceChanges). Without it no load reaches anything.
  void setExternalForce(ExternalForceFunction force, ExternalForceChanges changes);

  /// At the large-step boundary t0 with the state (u, v): switches parts fast and releases
  /// them; returns whether the fast parts changed, with the explanation in `reason`. A second
  /// call at the same boundary (a set-up before the first step) changes nothing and returns
  /// false; a time earlier than the last forgets the history (a new run).
  bool update(double t0, double largeStep, const Eigen::VectorXd& u, const Eigen::VectorXd& v, std::string& reason);

  /// The fast parts as regions (name, vertices, ratio).
  std::vector<AsyncRegion> regions() const;
  /// Every vertex of every part, fast or not (sorted, unique): on these a set-up that
  /// stands in must give exactly the ratio the policy gives now.
  std::vector<int> partVertices() const;
  const std::vector<LoadsSwitch>& switches() const { return switches_; }

 private:
  struct Part {
    std::string name;
    std::vector<int> vertices;
    int ratio = 2;
    std::vector<int> neighbourhood;
    bool fast = false;
    double peak = 0.0;
    int quiet = 0;
  };
  int addPart(std::string name, std::vector<int> vertices, int ratio);
  void switchFast(double t0, double largeStep, const std::vector<int>& reached, std::vector<std::string>& why);
  void releaseQuiet(double t0, const Eigen::VectorXd& u, const Eigen::VectorXd& v, const std::vector<char>& touched,
                    std::vector<std::string>& why);

  const TetMesh* mesh_;
  std::vector<char> hasFreeDof_;
  LoadsPolicySettings settings_;
  Eigen::VectorXd vertexMass_;
  ExternalForceFunction force_;
  ExternalForceChanges changes_;
  std::vector<Part> parts_;
  std::vector<std::vector<int>> partsOfVertex_;
  int givenParts_ = 0;
  int probeRatio_ = 2;
  double lastTime_ = -std::numeric_limits<double>::infinity();
  std::vector<LoadsSwitch> switches_;
};

}  // namespace asyncfem
