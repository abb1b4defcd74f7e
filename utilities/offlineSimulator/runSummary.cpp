// SPDX-License-Identifier: BSD-3-Clause
#include "runSummary.hpp"

#include <algorithm>
#include <asyncfem/integrator/multirateIntegrator.hpp>
#include <asyncfem/sceneIO/sceneObjects.hpp>
#include <asyncfem/simulationIO/checkpoint.hpp>
#include <cstdio>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <vector>

namespace offline {

std::string milliseconds(double seconds, int frames) {
  char text[32];
  std::snprintf(text, sizeof(text), "%9.3f ms", 1000.0 * seconds / frames);
  return text;
}

namespace {

// The first lines: frames and steps, mesh, model, regions, integrator report, set-up and
// the stability estimate. Leaves out fixed with precision 3.
void printRunHeader(std::ostream& out, const asyncfem::Scene& scene, const asyncfem::Simulation& simulation,
                    const RunRecord& record) {
  const asyncfem::FrameTiming& timing = simulation.timing;
  const std::optional<asyncfem::PaperCouplingCheck>& couplingCheck = record.couplingCheck;
  out << "offlineSimulator: " << scene.sourceName << ": " << (timing.frameCount - record.firstFrame) << " frames";
  if (record.firstFrame > 0) {
    out << " (resumed after frame " << record.firstFrame << " of " << timing.frameCount << ")";
  }
  out << ", " << (simulation.integrator->stats().steps - record.before.steps) << " steps of h = " << std::defaultfloat
      << std::setprecision(9) << simulation.integrator->timestep() << std::setprecision(3) << " ("
      << timing.stepsPerFrame << " per frame), " << std::fixed
      << (record.setupSeconds + record.loopSeconds + (couplingCheck ? couplingCheck->estimate.seconds : 0.0)) << " s\n";
  out << "  mesh        " << simulation.mesh->numVertices() << " vertices, " << simulation.mesh->numElements()
      << " elements, " << simulation.fixedVertices.size() << " fixed vertices\n";
  out << "  model       " << asyncfem::toString(simulation.problem->settings().forceModel)
      << (scene.forceModel != asyncfem::Scene::ForceModelKind::corotational ? ""
          : scene.tangent == asyncfem::Scene::Tangent::exact                ? " (exact tangent)"
                                                                            : " (simple tangent)")
      << ", " << (scene.mass == asyncfem::MassType::lumped ? "lumped" : "consistent") << " mass, integrator "
      << simulation.integrator->name() << "\n";
  const std::vector<asyncfem::RegionSummary> regions = asyncfem::regionSummaries(*simulation.integrator);
  if (!regions.empty()) {
    out << "  regions     " << regions.size() << " fast region" << (regions.size() == 1 ? "" : "s") << " (the rest, L, "
        << "steps at h):\n";
    for (std::size_t i = 0; i < regions.size(); ++i) {
      const asyncfem::RegionSummary& region = regions[i];
      out << "    S_" << (i + 1) << " '" << region.name << "': " << region.vertices << " vertices, "
          << region.interfaceDofs << " interface DOFs, m = " << region.ratio << " (h / " << region.ratio << ")\n";
    }
  }
  for (const std::string& line : simulation.integrator->report().lines) out << "  integrator  " << line << "\n";
  for (const std::string& line : asyncfem::surfaceContactSummary(simulation)) out << "  contact     " << line << "\n";
  out << "  setup       " << record.setupSeconds
      << " s (mesh, matrices, first factorization: " << record.before.factorizationSeconds << " s)\n";
  if (couplingCheck) {
    const asyncfem::StepGrowthEstimate& estimate = couplingCheck->estimate;
    out << "  stability   paper coupling, " << couplingCheck->regions << ": step growth estimate " << std::defaultfloat
        << std::setprecision(6) << estimate.spectralRadius << std::setprecision(3)
        << (estimate.converged ? "" : " (not converged)") << " from " << estimate.steps
        << " steps of the linearized scene, " << std::fixed << estimate.seconds << " s"
        << (couplingCheck->warning.empty() ? "" : " (WARNING above)") << "\n";
  }
}

// The frame loop's time per frame, phase by phase (this run's share of the statistics).
void printFrameTimes(std::ostream& out, const asyncfem::Simulation& simulation, const RunRecord& record) {
  const asyncfem::IntegratorStats& after = simulation.integrator->stats();
  const asyncfem::IntegratorStats& before = record.before;
  // Frames computed by this run (a resumed run starts at firstFrame).
  const int frames = std::max(simulation.timing.frameCount - record.firstFrame, 1);
  const double forces = after.forceSeconds - before.forceSeconds;
  const double assembly = after.assemblySeconds - before.assemblySeconds;
  const double factorization = after.factorizationSeconds - before.factorizationSeconds;
  const double solve = after.solveSeconds - before.solveSeconds;
  const double loopSeconds = record.loopSeconds;
  const double other = loopSeconds - forces - assembly - factorization - solve - record.outputSeconds;
  out << "  per frame   " << milliseconds(loopSeconds, frames) << "   (total " << loopSeconds << " s)\n";
  out << "    forces        " << milliseconds(forces, frames) << "\n";
  out << "    assembly      " << milliseconds(assembly, frames) << "\n";
  out << "    factorization " << milliseconds(factorization, frames) << "   ("
      << (after.factorizations - before.factorizations) << " factorizations in the run)\n";
  out << "    solve         " << milliseconds(solve, frames) << "   ("
      << (after.solvedRightHandSides - before.solvedRightHandSides) << " right-hand sides)\n";
  out << "    output        " << milliseconds(record.outputSeconds, frames) << "\n";
  if (other >= 0.0) {
    out << "    other         " << milliseconds(other, frames) << "   (vector updates, loads, state checks)\n";
  } else {
    // Phases timed on several threads at once (the regions of an asynchronous step, the
    // blocks of Z) add up to more than the wall time: there is no remainder to show.
    out << "    other                 -   (the phases above ran on several threads at once: their times add up to "
        << std::setprecision(3) << 1000.0 * (loopSeconds - other) / frames
        << " ms per frame, more than the wall time)\n";
  }
}

// What was skipped, what was checked, and where the output went.
void printRunTrailer(std::ostream& out, const asyncfem::Scene& scene, const asyncfem::Simulation& simulation,
                     const RunRecord& record) {
  out << "  skipped:\n";
  for (const std::string& item : simulation.integrator->stats().skipped) {
    out << "    - " << item << "\n";
  }
  for (const std::string& item : simulation.skipped) {
    out << "    - " << item << "\n";
  }
  const long long evaluations = simulation.monitor->energyEvaluations();
  out << "  checks      finite state and blow-up after every step; energy "
      << (evaluations > 0 ? std::to_string(evaluations) + " evaluations (once per frame after the loads)"
                          : std::string("not evaluated (see skipped)"))
      << "\n";
  out << "  output      " << scene.output.file.string() << " (" << simulation.timing.frameCount << " frames, "
      << record.outputBytes << " bytes; " << record.checkpointsWritten << " checkpoints, " << record.schedule.describe()
      << " and at the end, in " << asyncfem::checkpointPathFor(scene.output.file).string() << ")";
  if (!scene.output.vtuFolder.empty()) {
    out << ", .vtu files in " << scene.output.vtuFolder.string();
  }
  out << "\n";
}

}  // namespace

void printSummary(const asyncfem::Scene& scene, const asyncfem::Simulation& simulation, const RunRecord& record) {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(3);
  printRunHeader(out, scene, simulation, record);
  printFrameTimes(out, simulation, record);
  printRunTrailer(out, scene, simulation, record);
  std::cout << out.str() << std::flush;
}

}  // namespace offline
