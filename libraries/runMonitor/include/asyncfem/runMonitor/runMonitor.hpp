// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <asyncfem/core/error.hpp>
#include <asyncfem/integrator/integrator.hpp>
#include <asyncfem/problem/problem.hpp>
#include <asyncfem/simulationIO/checkpoint.hpp>
#include <asyncfem/simulationIO/simulationFile.hpp>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace asyncfem {

/// Watches a run for numerical failure, so that no unstable state is ever stored:
/// - after every step, u and v finite and max |u| <= blowUpFactor x the rest bounding-box
///   diagonal;
/// - after every step, for a hyperelastic model without inversion handling (no
///   inversionThreshold), no element inverted (det F <= 0): such a model's energy only
///   sees J^2, so an inverted element would go on as if it were a mirrored one;
/// - after every frame, once no load window changes any more (Loads::lastWindowChange()),
///   the total energy E = kinetic + elastic + contact penalty (PenaltyContact::energy)
///   - constant loads . u has not grown by more than 9 times its size at the start of that
///   free phase (a stable integrator keeps or dissipates it; explicit ones let it
///   oscillate by far less; with contact the size is at least the constant loads' work
///   over the rest bounding-box diagonal, sum_v |f_v| times it, since a body dropped from
///   rest starts at zero).
/// Failures throw asyncfem::NumericalError whose location() carries the frame, step,
/// time, vertex and region, and whose message says the same in words.
class RunMonitor {
 public:
  struct Settings {
    double blowUpFactor = 1000.0;
    bool energyCheck = true;
  };
  /// The step size is the integrator's (Integrator::timestep()), read at every frame.
  RunMonitor(const Problem& problem, Settings settings);
  explicit RunMonitor(const Problem& problem) : RunMonitor(problem, Settings{}) {}

  /// Runs stepsPerFrame steps of integrator with the checks; frame is the 0-based frame
  /// index used in messages and locations.
  void advanceFrame(Integrator& integrator, long long frame, int stepsPerFrame);

  /// "vertex 17 in fast region S_1 'tip' (vertex set 'tip')", for messages.
  std::string describeVertex(const Integrator& integrator, int vertex) const;

  double blowUpDisplacement() const { return blowUpDisplacement_; }
  double boundingBoxDiagonal() const { return boundingBoxDiagonal_; }
  /// Time from which the energy check runs (infinity: never).
  double energyCheckFrom() const { return energyCheckFrom_; }
  /// Energy evaluations made so far (one per frame in the free phase).
  long long energyEvaluations() const { return energyEvaluations_; }
  /// Checks the settings or the problem made unnecessary, for run summaries.
  std::vector<std::string> skipped() const;
  /// What the checks carry from frame to frame: the energy check's reference (energy,
  /// scale, time) once the free phase has begun, else empty. A resumed run restores it
  /// with setState(), so that its energy check compares with the same reference as an
  /// uninterrupted run's (and stops at the same frame).
  Eigen::VectorXd state() const;
  /// Restores state(); asyncfem::Error for a vector of another size (0 or 3).
  void setState(const Eigen::VectorXd& state);

 private:
  NumericalErrorLocation locate(const Integrator& integrator, long long frame, long long step, double time,
                                int vertex) const;
  /// One step with the finiteness and blow-up checks; step is 1-based over the run.
  void checkedStep(Integrator& integrator, long long frame, long long step) const;
  /// Throws when u or v is not finite or max |u| exceeds the blow-up limit.
  void checkState(const Integrator& integrator, long long frame, long long step, double stepEnd,
                  const std::string& where) const;
  /// Throws when an element inverted under a model that cannot handle it.
  void checkInversion(const Integrator& integrator, long long frame, long long step, double stepEnd,
                      const std::string& where) const;
  /// The energy check at the end of a frame.
  void checkEnergy(const Integrator& integrator, long long frame);

  const TetMesh* mesh_;
  Settings settings_;
  double boundingBoxDiagonal_ = 0.0;
  double blowUpDisplacement_ = 0.0;
  double energyCheckFrom_ = std::numeric_limits<double>::infinity();
  Eigen::VectorXd constantLoad_;
  std::shared_ptr<const PenaltyContact> contact_;  // its potential enters the energy
  double loadWorkScale_ = 0.0;                     // with contact: sum_v |f_v| x the diagonal
  bool haveFreeEnergy_ = false;
  double freeEnergy_ = 0.0, freeEnergyScale_ = 0.0, freeEnergyTime_ = 0.0;
  long long energyEvaluations_ = 0;
  /// The force model's name when the inversion check runs, empty otherwise.
  std::string inversionCheckModel_;
  /// What the inversion check's message advises (the options that give the model inversion
  /// handling), when it runs.
  std::string inversionAdvice_;
  /// Each element's Jacobian determinants at rest, one per tetrahedron (its edge matrix
  /// (x1 - x0, x2 - x0, x3 - x0)), eight per hexahedron (its corners'), element after element.
  std::vector<double> restJacobians_;
};

/// When a run writes its checkpoint: every `everyFrames` frames (0: not by frames) and/or
/// when `everySeconds` of wall time have passed since the last one (0: not by time); a
/// run's last frame and an interrupted run always get one. Default: every 30 s, so that a
/// checkpoint never costs a noticeable share of a run whose frames are cheap.
struct CheckpointSchedule {
  int everyFrames = 0;
  double everySeconds = 30.0;

  /// Whether to write after the frame that makes framesDone finished frames, given the
  /// wall-clock seconds since the last checkpoint.
  bool due(long long framesDone, double secondsSinceLast) const {
    return (everyFrames > 0 && framesDone % everyFrames == 0) ||
           (everySeconds > 0.0 && secondsSinceLast >= everySeconds);
  }
  /// "every 30 s of wall time", "every 5 frames", "every 2 frames or 30 s".
  std::string describe() const;
};

/// Identity of a run, stored in its checkpoint so that a resumed run refuses a file
/// written with other physics: sceneText (the scene as JSON text, without the keys a
/// resumed run may change), the integrator name, h, the frame interval, and the problem
/// as built (rest positions, elements, materials, fixed vertices).
std::uint32_t runFingerprint(const std::string& sceneText, const std::string& integratorName, double timestep,
                             double frameInterval, const Problem& problem);

/// Fingerprint of what a reader of a run's frames needs from its problem: rest positions,
/// elements and fixed vertices (CRC-32). Stored in the .afsim header next to the scene path.
std::uint32_t problemFingerprint(const Problem& problem);

/// The checkpoint of integrator's state after `frames` finished frames, with the
/// monitor's state when one is given.
SimulationCheckpoint captureCheckpoint(const Integrator& integrator, std::int64_t frames, std::uint32_t fingerprint,
                                       const RunMonitor* monitor = nullptr);

/// What differs between the run that wrote an output (its header `stored` and its
/// checkpoint) and this one (`integrator`, `header`), one "what (there ..., here ...)"
/// per field; when only the fingerprint differs, a sentence naming the scene or mesh.
std::vector<std::string> runDifferences(const SimulationCheckpoint& checkpoint, const SimulationFileHeader& stored,
                                        const Integrator& integrator, const SimulationFileHeader& header,
                                        bool fingerprintDiffers);

/// The same for a run whose state is not an Integrator's (the PETSc backend's): the
/// integrator named integratorName with a state of numDofs values.
std::vector<std::string> runDifferences(const SimulationCheckpoint& checkpoint, const SimulationFileHeader& stored,
                                        const std::string& integratorName, std::int64_t numDofs,
                                        const SimulationFileHeader& header, bool fingerprintDiffers);

/// The checks of resumeFromCheckpoint() (below) for a run whose state is not an
/// Integrator's: integratorName and numDofs stand for the integrator's name() and state
/// size. Returns the checkpoint to continue from; restores nothing. Throws as
/// resumeFromCheckpoint() does.
SimulationCheckpoint checkpointToResume(const std::filesystem::path& output, const SimulationFileHeader& header,
                                        std::uint32_t fingerprint, std::int64_t requestedFrames,
                                        const std::string& integratorName, std::int64_t numDofs);

/// Continues an interrupted run: reads the checkpoint next to output (checkpointPathFor),
/// checks that output and checkpoint were written by this run (runDifferences against
/// header and fingerprint), that requestedFrames is not below the frames already finished,
/// and that the output's last kept record holds exactly the checkpoint's state; then
/// restores the state into integrator (and the monitor's, when one is given) and returns
/// the frames to keep. Throws
/// asyncfem::Error "cannot resume: ..." naming what differs or what is missing.
std::int64_t resumeFromCheckpoint(const std::filesystem::path& output, const SimulationFileHeader& header,
                                  std::uint32_t fingerprint, std::int64_t requestedFrames, Integrator& integrator,
                                  RunMonitor* monitor = nullptr);

}  // namespace asyncfem
