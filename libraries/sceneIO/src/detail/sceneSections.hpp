// SPDX-License-Identifier: BSD-3-Clause
// Sections of the scene parser that live in their own files. Private to the library.
#pragma once

#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/settings/jsonReader.hpp>

namespace asyncfem::detail {

/// Reads the "forceModel" section into scene.forceModel and scene.hyperelastic (errors name
/// the key under forceModel).
void parseForceModel(JsonObjectReader& top, Scene& scene);

}  // namespace asyncfem::detail
