// SPDX-License-Identifier: BSD-3-Clause
// afsimTool intersections: the exact surface intersection check of every chosen frame.
#pragma once

#include <optional>
#include <string>

namespace afsimtool {

/// Per chosen frame of the .afsim file at simulation, on the scene at scene (or the scene the
/// file records): the pairs of the bodies' boundary triangles that intersect (within a body,
/// neighbours sharing a vertex left out, and between bodies), the pairs of a body triangle
/// and a mesh obstacle's triangle (obstacles where their paths put them at the frame's time)
/// that intersect, and the contact depth (PenaltyContact::maxPenetration: below the ground,
/// planes and spheres, or into the surfaces' contact layer of thickness dhat, which is not
/// an intersection).
/// One CSV row per frame on stdout, then a summary line on stderr. Returns 0; throws
/// asyncfem::Error for a file or scene that cannot be read or does not match.
int intersections(const std::string& simulation, const std::optional<std::string>& scene, const std::string& frames);

}  // namespace afsimtool
