// SPDX-License-Identifier: BSD-3-Clause
// The performance table (the columns of Table 1 of Zhao, Li & Barbič 2016) for every
// shipped scene.
#pragma once

#include <string>

namespace asyncfem::bench {

/// For every scene models/*/*.json (sorted) whose integrator is "async": vertices, tets,
/// |S_i| (vertices per fast region), hL, m_i, and the wall time per frame (median over
/// repeats, frame 0 excluded) of the async run, of rotation-strain warping of its frames,
/// and of single-rate backward Euler at hL and at hS = hL / max m_i. Prints Markdown to
/// stdout and writes outFolder/performance-table.md. Returns the exit status (0).
int printPerformanceTable(const std::string& modelsFolder, int frames, int repeats, const std::string& outFolder);

}  // namespace asyncfem::bench
