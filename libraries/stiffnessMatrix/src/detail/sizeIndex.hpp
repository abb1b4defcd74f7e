// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <cstddef>

namespace asyncfem::detail {

using Index = std::size_t;

/// A non-negative int (a vertex, DOF or entry number) as a std::vector index.
inline Index toIndex(int i) { return static_cast<Index>(i); }

}  // namespace asyncfem::detail
