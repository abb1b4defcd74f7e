// SPDX-License-Identifier: BSD-3-Clause
#include <Eigen/Dense>
#include <algorithm>
#include <asyncfem/benchmarkTools/modalReference.hpp>
#include <asyncfem/core/error.hpp>
#include <asyncfem/modalAnalysis/generalizedEigen.hpp>
#include <cmath>
#include <limits>
#include <string>

namespace asyncfem {

void advanceDampedOscillator(double lambda, double damping, double force, double duration, double& position,
                             double& rate) {
  const double tau = duration;
  if (tau <= 0.0) return;
  const double c = damping;
  if (lambda <= 0.0) {
    // Rigid mode: q'' + c q' = p.
    if (c * tau < 1e-8) {
      position += rate * tau + 0.5 * force * tau * tau;
      rate += force * tau;
      return;
    }
    const double decay = std::exp(-c * tau);
    const double steady = force / c;
    // q' = steady + (q'_0 - steady) e^{-c t}; q = q_0 + steady t + (q'_0 - steady)(1 - e^{-c t}) / c
    position += steady * tau + (rate - steady) * (-std::expm1(-c * tau)) / c;
    rate = steady + (rate - steady) * decay;
    return;
  }
  const double equilibrium = force / lambda;
  const double x0 = position - equilibrium;
  const double r0 = rate;
  const double mu = 0.5 * c;
  const double discriminant = mu * mu - lambda;  // g^2
  // e^{-mu tau} cosh(g tau) =: a and e^{-mu tau} sinh(g tau) / g =: b, then
  // exp(A tau) = a I + b (A + mu I), A + mu I = [mu 1; -lambda -mu].
  double a = 0.0, b = 0.0;
  const double scale = std::max(mu * mu, lambda);
  if (std::abs(discriminant) <= 1e-12 * scale) {
    const double decay = std::exp(-mu * tau);
    a = decay;
    b = decay * tau;
  } else if (discriminant < 0.0) {
    const double omega = std::sqrt(-discriminant);
    const double decay = std::exp(-mu * tau);
    a = decay * std::cos(omega * tau);
    b = decay * std::sin(omega * tau) / omega;
  } else {
    const double g = std::sqrt(discriminant);
    const double slow = -lambda / (mu + g);  // g - mu, without cancellation
    const double fast = -(g + mu);
    const double eSlow = std::exp(slow * tau), eFast = std::exp(fast * tau);
    a = 0.5 * (eSlow + eFast);
    b = 0.5 * (eSlow - eFast) / g;
  }
  const double x = a * x0 + b * (mu * x0 + r0);
  const double r = a * r0 + b * (-lambda * x0 - mu * r0);
  position = equilibrium + x;
  rate = r;
}

ModalReference::ModalReference(const Eigen::SparseMatrix<double>& mass, const Eigen::SparseMatrix<double>& stiffness,
                               const FreeDofs& freeDofs, double alpha, double beta)
    : freeDofs_(freeDofs), alpha_(alpha), beta_(beta) {
  const std::vector<int>& free = freeDofs.freeToFull();
  const Eigen::Index n = static_cast<Eigen::Index>(free.size());
  SubmatrixExtractor extractor(mass, free, free);
  freeMass_ = extractor.extract(mass);
  Eigen::MatrixXd denseMass = Eigen::MatrixXd(freeMass_);
  Eigen::MatrixXd denseStiffness = Eigen::MatrixXd(SubmatrixExtractor(stiffness, free, free).extract(stiffness));
  if (!solveGeneralizedEigen(denseStiffness, denseMass, eigenvalues_)) {
    throw NumericalError("modal reference: generalized eigendecomposition of the " + std::to_string(n) +
                         " free DOFs failed (is the mass matrix positive definite on them?)");
  }
  modes_ = std::move(denseStiffness);
}

std::string ModalReference::backend() { return generalizedEigenBackend(); }

namespace {

void checkTimesAndBreakpoints(const PiecewiseConstantLoad& load, const std::vector<double>& times) {
  for (std::size_t k = 0; k < times.size(); ++k) {
    if (!(times[k] >= 0.0) || (k > 0 && times[k] < times[k - 1])) {
      throw Error("modal reference: requested times must be >= 0 and ascending (entry " + std::to_string(k) + ")");
    }
  }
  if (load.forces.size() != load.breakpoints.size() + 1) {
    throw Error("modal reference: a piecewise-constant load needs breakpoints.size() + 1 force vectors");
  }
  for (std::size_t k = 0; k < load.breakpoints.size(); ++k) {
    if (!(load.breakpoints[k] > 0.0) || (k > 0 && load.breakpoints[k] <= load.breakpoints[k - 1])) {
      throw Error("modal reference: load breakpoints must be > 0 and strictly ascending (entry " + std::to_string(k) +
                  ")");
    }
  }
}

// Full vectors are empty (zero) or 3n long; checked in the order the errors were always
// reported: initial state, load vectors, impulses.
void checkSizes(const PiecewiseConstantLoad& load, const Eigen::VectorXd& initialDisplacement,
                const Eigen::VectorXd& initialVelocity, int numDofs) {
  const auto checkSize = [numDofs](const Eigen::VectorXd& v, const std::string& what) {
    if (v.size() != 0 && v.size() != numDofs) {
      throw Error("modal reference: " + what + " has " + std::to_string(v.size()) + " entries, expected " +
                  std::to_string(numDofs));
    }
  };
  checkSize(initialDisplacement, "the initial displacement");
  checkSize(initialVelocity, "the initial velocity");
  for (const Eigen::VectorXd& f : load.forces) checkSize(f, "a load vector");
  for (const PiecewiseConstantLoad::Impulse& impulse : load.impulses) checkSize(impulse.impulse, "an impulse");
}

// What happens at a time: a requested output, an impulse, a load change. At equal times
// they happen in this order (an output records the state before an impulse at its time).
enum class EventKind { output, impulse, breakpoint };

struct Event {
  double time;
  EventKind kind;
  std::size_t index;  // into times, load.impulses or load.breakpoints
};

std::vector<Event> sortedEvents(const PiecewiseConstantLoad& load, const std::vector<double>& times) {
  std::vector<Event> events;
  for (std::size_t k = 0; k < times.size(); ++k) events.push_back({times[k], EventKind::output, k});
  for (std::size_t k = 0; k < load.impulses.size(); ++k) {
    events.push_back({load.impulses[k].time, EventKind::impulse, k});
  }
  for (std::size_t k = 0; k < load.breakpoints.size(); ++k) {
    events.push_back({load.breakpoints[k], EventKind::breakpoint, k});
  }
  std::stable_sort(events.begin(), events.end(), [](const Event& a, const Event& b) {
    return a.time < b.time || (a.time == b.time && a.kind < b.kind);
  });
  return events;
}

}  // namespace

std::vector<Eigen::VectorXd> ModalReference::displacements(const PiecewiseConstantLoad& load,
                                                           const std::vector<double>& times,
                                                           const Eigen::VectorXd& initialDisplacement,
                                                           const Eigen::VectorXd& initialVelocity) const {
  const Eigen::Index n = eigenvalues_.size();
  checkTimesAndBreakpoints(load, times);
  checkSizes(load, initialDisplacement, initialVelocity, freeDofs_.numDofs());
  // Modal coordinates: q = Phi^T M u (Phi M-orthonormal), modal force Phi^T f.
  auto modal = [&](const Eigen::VectorXd& full, bool weightByMass) -> Eigen::VectorXd {
    if (full.size() == 0) return Eigen::VectorXd::Zero(n);
    const Eigen::VectorXd restricted = freeDofs_.restrict(full);
    if (weightByMass) return modes_.transpose() * (freeMass_ * restricted);
    return modes_.transpose() * restricted;
  };
  std::vector<Eigen::VectorXd> modalForces;
  for (const Eigen::VectorXd& f : load.forces) modalForces.push_back(modal(f, false));
  std::vector<Eigen::VectorXd> modalImpulses;
  for (const PiecewiseConstantLoad::Impulse& impulse : load.impulses) {
    modalImpulses.push_back(modal(impulse.impulse, false));
  }
  Eigen::VectorXd q = modal(initialDisplacement, true);
  Eigen::VectorXd rate = modal(initialVelocity, true);
  const Eigen::VectorXd damping = alpha_ * Eigen::VectorXd::Ones(n) + beta_ * eigenvalues_;
  // Rigid modes: eigenvalues at round-off level relative to the largest.
  const double rigidBelow = 1e-12 * std::max(1.0, eigenvalues_.size() > 0 ? eigenvalues_.maxCoeff() : 1.0);

  std::vector<Eigen::VectorXd> out(times.size());
  double now = 0.0;
  std::size_t piece = 0;
  for (const Event& event : sortedEvents(load, times)) {
    const double duration = event.time - now;
    if (duration > 0.0) {
      const Eigen::VectorXd& p = modalForces[piece];
      for (Eigen::Index j = 0; j < n; ++j) {
        const double lambda = eigenvalues_[j] <= rigidBelow ? 0.0 : eigenvalues_[j];
        advanceDampedOscillator(lambda, damping[j], p[j], duration, q[j], rate[j]);
      }
      now = event.time;
    }
    if (event.kind == EventKind::output) {
      out[event.index] = freeDofs_.expand(modes_ * q);
    } else if (event.kind == EventKind::impulse) {
      rate += modalImpulses[event.index];
    } else {
      piece = event.index + 1;
    }
  }
  return out;
}

Eigen::VectorXd ModalReference::modalCoordinates(const Eigen::VectorXd& displacement) const {
  const Eigen::Index numDofs = freeDofs_.numDofs();
  if (displacement.size() != numDofs) {
    throw Error("modal reference: a displacement has " + std::to_string(displacement.size()) + " entries, expected " +
                std::to_string(numDofs));
  }
  return modes_.transpose() * (freeMass_ * freeDofs_.restrict(displacement));
}

std::vector<Eigen::VectorXd> modalTrajectory(const ModalReference& modal, const std::vector<Eigen::VectorXd>& run) {
  std::vector<Eigen::VectorXd> out;
  out.reserve(run.size());
  for (const Eigen::VectorXd& u : run) out.push_back(modal.modalCoordinates(u));
  return out;
}

std::vector<ModalBand> motionKeptPerBand(const Eigen::VectorXd& eigenvalues,
                                         const std::vector<Eigen::VectorXd>& runModal,
                                         const std::vector<Eigen::VectorXd>& referenceModal,
                                         const std::vector<double>& bandEdges) {
  if (bandEdges.empty() || bandEdges.front() < 0.0 || !std::is_sorted(bandEdges.begin(), bandEdges.end())) {
    throw Error("motionKeptPerBand: band edges must be ascending and >= 0");
  }
  const Eigen::VectorXd& lambda = eigenvalues;
  std::vector<ModalBand> bands(bandEdges.size());
  std::vector<int> bandOf(static_cast<std::size_t>(lambda.size()), -1);
  for (std::size_t b = 0; b < bands.size(); ++b) {
    bands[b].lowOmega = bandEdges[b];
    bands[b].highOmega = b + 1 < bandEdges.size() ? bandEdges[b + 1] : std::numeric_limits<double>::infinity();
  }
  for (Eigen::Index j = 0; j < lambda.size(); ++j) {
    const double omega = std::sqrt(std::max(0.0, lambda[j]));
    for (std::size_t b = 0; b < bands.size(); ++b) {
      if (omega >= bands[b].lowOmega && omega < bands[b].highOmega) {
        bandOf[static_cast<std::size_t>(j)] = static_cast<int>(b);
        ++bands[b].modes;
        break;
      }
    }
  }
  std::vector<double> runSum(bands.size(), 0.0), referenceSum(bands.size(), 0.0);
  const std::size_t frames = std::min(runModal.size(), referenceModal.size());
  for (std::size_t k = 0; k < frames; ++k) {
    const Eigen::VectorXd& q = runModal[k];
    const Eigen::VectorXd& r = referenceModal[k];
    for (Eigen::Index j = 0; j < q.size(); ++j) {
      const int b = bandOf[static_cast<std::size_t>(j)];
      if (b < 0) continue;
      runSum[static_cast<std::size_t>(b)] += q[j] * q[j];
      referenceSum[static_cast<std::size_t>(b)] += r[j] * r[j];
    }
  }
  for (std::size_t b = 0; b < bands.size(); ++b) {
    bands[b].kept =
        referenceSum[b] > 0.0 ? std::sqrt(runSum[b] / referenceSum[b]) : std::numeric_limits<double>::quiet_NaN();
  }
  return bands;
}

std::vector<ModalBand> motionKeptPerBand(const ModalReference& modal, const std::vector<Eigen::VectorXd>& run,
                                         const std::vector<Eigen::VectorXd>& reference,
                                         const std::vector<double>& bandEdges) {
  const std::size_t frames = std::min(run.size(), reference.size());
  const std::vector<Eigen::VectorXd> runFrames(run.begin(), run.begin() + static_cast<std::ptrdiff_t>(frames));
  const std::vector<Eigen::VectorXd> referenceFrames(reference.begin(),
                                                     reference.begin() + static_cast<std::ptrdiff_t>(frames));
  return motionKeptPerBand(modal.eigenvalues(), modalTrajectory(modal, runFrames),
                           modalTrajectory(modal, referenceFrames), bandEdges);
}

}  // namespace asyncfem
