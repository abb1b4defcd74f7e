// SPDX-License-Identifier: BSD-3-Clause
// What a benchmark's errors are measured against: the reference trajectory, and the vertex
// groups the errors are reported on.
#pragma once

#include <asyncfem/benchmarkTools/benchmarkRun.hpp>
#include <asyncfem/benchmarkTools/errorMetrics.hpp>
#include <asyncfem/benchmarkTools/modalReference.hpp>
#include <memory>
#include <string>
#include <vector>

namespace asyncfem {

/// Which reference computeReference() uses: the exact modal solution when the scene allows
/// it, else a fine trapezoidal run (automatic); the modal one or an error (modal); the
/// trapezoidal run in any case (trapezoidal).
enum class ReferenceKind { automatic, modal, trapezoidal };

struct BenchmarkReference {
  std::string description;                      ///< one line for reports: which reference, how fine, how long it took
  Trajectory frames;                            ///< full (3n) displacement after every frame
  std::shared_ptr<const ModalReference> modal;  ///< set when the reference is the exact modal solution
};

/// Steps per frame of the trapezoidal reference: frame interval / (h_min / 4), h_min
/// the smallest step any configuration takes (its step divided by the largest ratio of the
/// regions it resolves to, configurationRegions(): proposed regions included), at most
/// the frame interval. A quarter of the smallest step makes the reference's own O(h^2)
/// error about 16 times smaller than the finest configuration's would be at second order.
int referenceStepsPerFrame(const Scene& scene, const Simulation& baseline,
                           const std::vector<BenchmarkConfiguration>& configurations);

/// The reference for `frames` frames of the scene: the exact modal solution
/// (ModalReference of the linear K at rest, the scene's mass and Rayleigh damping, loaded
/// by sceneLoad()) when kind allows it and modalReferenceUnsupportedReason() is empty, else
/// a trapezoidal run at referenceStepsPerFrame() (design note, "What accurate means
/// here"). baseline: a single-rate build of the scene. Throws asyncfem::Error for
/// ReferenceKind::modal on a scene without a modal reference, and when the trapezoidal run
/// fails.
BenchmarkReference computeReference(const Scene& scene, const Simulation& baseline,
                                    const std::vector<BenchmarkConfiguration>& configurations, int frames,
                                    ReferenceKind kind, int maxModalDofs);

/// Vertex groups for the errors: each fast region of the first multirate configuration
/// (its name, or "S<k>" when it has none), "L" (every other vertex, left out when empty)
/// and "all" (no vertex list: every vertex). Only "all" without a multirate configuration.
std::vector<VertexGroup> errorGroups(const Scene& scene, const Simulation& baseline,
                                     const std::vector<BenchmarkConfiguration>& configurations);

/// The vertex of the first group (when there are others besides "all"; else of the whole
/// mesh of numVertices vertices) whose displacement |u_k(v)| peaks highest over the
/// reference's frames; the lowest id among equal peaks.
int chooseVertex(const Trajectory& reference, const std::vector<VertexGroup>& groups, int numVertices);

}  // namespace asyncfem
