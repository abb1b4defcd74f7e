// SPDX-License-Identifier: BSD-3-Clause
// Task parallelism over fast regions and blocks of Z columns. Private to the library.
#pragma once

#include <omp.h>

#include <algorithm>
#include <asyncfem/core/threading.hpp>
#include <exception>
#include <vector>

namespace asyncfem::detail {

/// Threads to use for a request: requested when positive, else OpenMP's maximum.
inline int threadBudget(int requested) { return requested > 0 ? requested : std::max(1, omp_get_max_threads()); }

/// Runs body(t) for t = 0..count-1 on up to `threads` OpenMP threads and rethrows the first
/// exception a task threw (an exception must not leave an OpenMP region); one task or one
/// thread: in this thread, outside any OpenMP region.
template <class Body>
void parallelTasks(int count, int threads, const Body& body) {
  if (count <= 1 || threads <= 1) {
    // No OpenMP region at all: a solver's own parallel regions inside body (CHOLMOD's
    // supernodal factorization) then run at the top level on OpenMP's pooled threads.
    // Inside even a one-thread region they are nested, and libgomp starts and joins new
    // threads for each of them (hundreds per large step on the beam scene).
    for (int t = 0; t < count; ++t) body(t);
    return;
  }
  std::vector<std::exception_ptr> failures(static_cast<std::size_t>(std::max(count, 0)));
  // The tasks' solver calls run side by side: the BLAS starting teams of its own inside
  // each would put more threads than cores.
  const ScopedBlasThreads oneBlasThread(1);
#pragma omp parallel for schedule(dynamic) num_threads(std::max(1, std::min(threads, count))) if (count > 1)
  for (int t = 0; t < count; ++t) {
    try {
      body(t);
    } catch (...) {
      failures[static_cast<std::size_t>(t)] = std::current_exception();
    }
  }
  for (const std::exception_ptr& failure : failures)
    if (failure) std::rethrow_exception(failure);
}

}  // namespace asyncfem::detail
