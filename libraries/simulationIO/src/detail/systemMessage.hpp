// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <cerrno>
#include <cstring>
#include <string>

namespace asyncfem::detail {

/// The text of the last system call's error (errno).
inline std::string systemMessage() { return std::strerror(errno); }

}  // namespace asyncfem::detail
