// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <asyncfem/contact/penaltyContact.hpp>
#include <limits>
#include <memory>
#include <vector>

namespace asyncfem {

/// The same force on each of a list of vertices while a window is open.
struct VertexLoad {
  std::vector<int> vertices;                            ///< sorted, unique, 0-based
  Eigen::Vector3d perVertex = Eigen::Vector3d::Zero();  ///< force on each vertex
  double start = 0.0;                                   ///< acts for start <= t < end ...
  double end = std::numeric_limits<double>::infinity();
  bool leftOpen = false;  ///< ... or for start < t <= end (impulses)

  bool active(double time) const { return leftOpen ? (time > start && time <= end) : (time >= start && time < end); }
};

/// The external force of a problem: a constant part (gravity M g), windowed vertex
/// loads (pulls, impulses) and penalty contact, as a value that can be asked questions
/// (when does it change, what is constant) rather than a closure.
///
/// Time convention (docs/scene-format.md, "forces"): step times are k h and a window
/// bound within 1e-9 h of a step time counts as that step time, so a window [a, b)
/// acts at the step times a <= k h < b exactly, whatever the round-off of k h.
class Loads {
 public:
  /// A force constant in time (gravity M g; size 3n), added to any set before.
  void addConstant(const Eigen::VectorXd& force);
  /// A vertex load acting for start <= t < end (end may be infinite).
  void addWindow(VertexLoad load);
  /// Penalty contact (explicit, state dependent). Null: none.
  void setContact(std::shared_ptr<const PenaltyContact> contact) { contact_ = std::move(contact); }

  /// Adds f_ext(t, u, v) to forces (size 3n).
  void addTo(double time, const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity,
             Eigen::VectorXd& forces) const;
  /// Adds f_ext(t, u, v) at the listed vertices only (ascending) to forces, the same values
  /// as addTo, added in the same order; the other entries are left as they are.
  void addTo(double time, const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity,
             const std::vector<int>& vertices, Eigen::VectorXd& forces) const;
  /// The terms of f_ext(t, u, v) of rank owner (PenaltyContact::addForcesOfRank): the
  /// per-vertex loads and obstacle forces at the listed vertices (ascending) and the surface
  /// contact pairs whose highest vertex rank is owner, on all their vertices; jacobian, where
  /// not null, the contact's derivatives from the same evaluation (cleared first; the loads
  /// have none).
  void addTo(double time, const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity,
             const std::vector<int>& vertices, const std::vector<int>& rank, int owner, Eigen::VectorXd& forces,
             VertexJacobian* jacobian = nullptr) const;
  /// Times at which the force changes (window bounds), sorted, unique, finite.
  std::vector<double> breakpoints() const;
  /// From this time on no load changes: the last finite window bound (0 when there is
  /// none); +infinity with contact, whose force depends on the state.
  double lastChange() const;
  /// The last finite window bound (0 when there is none), contact aside: from this time on
  /// only the constant part and the contact act.
  double lastWindowChange() const;
  /// The force acting at every t >= lastChange() without contact (constant part plus the
  /// windows that never close), size numDofs.
  Eigen::VectorXd constantPart(Eigen::Index numDofs) const;

  bool empty() const { return constant_.size() == 0 && windows_.empty() && !contact_; }
  bool hasConstant() const { return constant_.size() > 0; }
  const std::vector<VertexLoad>& windows() const { return windows_; }
  const std::shared_ptr<const PenaltyContact>& contact() const { return contact_; }

 private:
  /// The constant part and the open windows at the listed vertices.
  void addVertexLoads(double time, const std::vector<int>& vertices, Eigen::VectorXd& forces) const;

  Eigen::VectorXd constant_;
  std::vector<VertexLoad> windows_;
  std::shared_ptr<const PenaltyContact> contact_;
};

}  // namespace asyncfem
