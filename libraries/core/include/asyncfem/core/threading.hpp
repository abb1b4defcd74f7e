// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <dlfcn.h>
#include <link.h>
#include <unistd.h>

#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <cstdlib>
#include <cstring>
#include <string>

namespace asyncfem {

/// Makes idle OpenMP threads sleep instead of spinning, for command-line programs.
///
/// The element loops run on OpenMP threads and CHOLMOD's supernodal kernels on the BLAS's
/// own threads. With the OpenMP runtime's default policy, threads that just left a
/// parallel loop keep spinning and take the cores the BLAS threads need: on a 2-core
/// machine a numeric factorization was measured 25x slower. The policy can only be set
/// through the environment before the runtime starts, so when OMP_WAIT_POLICY is unset
/// this sets it to "passive" and re-executes the program once (same arguments). A user's
/// own OMP_WAIT_POLICY is respected. Call it first thing in main().
inline void preferPassiveThreadWaiting(char** argv) {
  if (std::getenv("OMP_WAIT_POLICY") != nullptr) return;
  ::setenv("OMP_WAIT_POLICY", "passive", 1);
  ::execv("/proc/self/exe", argv);
  // execv only returns on failure (no /proc): carry on with the default policy.
}

/// The thread count the sparse factorizations and solves give the BLAS: the environment
/// variable ASYNCFEM_BLAS_THREADS (a positive integer), 1 where it is unset. A setting, not a
/// reading of the machine, for two reasons. The last bits of a factor depend on the BLAS's
/// thread count (OpenBLAS's dpotrf and dgemm split their sums between threads: 7e-15 and
/// 1.4e-14 apart on 2 cores, sparseSolverTests BlasResults.*), so a count that followed the
/// load would make a run's trajectory, and a resumed run, depend on what else the machine
/// was doing. And beside other work OpenBLAS's threads wait on each other (a 45k-DOF
/// factorization took 30 s instead of 0.7 s beside two busy processes on 2 cores). One
/// thread costs an idle machine's largest factorizations up to 1.3x on 2 cores; a user who
/// owns the cores can give more (and gets trajectories that depend on that number only).
/// Throws asyncfem::Error naming the variable for a value that is not a positive integer.
inline int factorBlasThreads() {
  const char* text = std::getenv("ASYNCFEM_BLAS_THREADS");
  if (text == nullptr || text[0] == '\0') return 1;
  char* end = nullptr;
  const long value = std::strtol(text, &end, 10);
  if (*end != '\0' || value < 1 || value > 4096) {
    throw Error(std::string("ASYNCFEM_BLAS_THREADS: expected a positive integer (at most 4096), got \"") + text + "\"");
  }
  return static_cast<int>(value);
}

/// While alive, the BLAS runs each of its calls on at most `threads` threads of its own, then
/// its previous count returns. For code that calls the BLAS (CHOLMOD's supernodal solves
/// and factorizations) from several OpenMP threads at once: each call would otherwise start
/// a team of the BLAS's threads on the same cores, which then compete with the OpenMP
/// threads (on 2 cores the corotational dinosaur's asynchronous large step took 44 to 48 ms
/// on average, 29 ms with the BLAS held to one thread; docs/benchmarks.md). It acts on OpenBLAS,
/// found in the process at run time (openblas_set_num_threads); with another BLAS it does
/// nothing. The count is process-wide: create it in the thread that starts the parallel
/// region, not inside it.
class ScopedBlasThreads {
 public:
  explicit ScopedBlasThreads(int threads) : threads_(threads) {
    int (*get)() = nullptr;
    symbol("openblas_get_num_threads", get);
    symbol("openblas_set_num_threads", set_);
    if (get == nullptr || set_ == nullptr) {
      set_ = nullptr;
      return;
    }
    previous_ = get();
    current_ = previous_;
    hold(true);
  }
  ~ScopedBlasThreads() { hold(false); }
  /// The BLAS's thread count before this guard (0 where the BLAS is not OpenBLAS).
  int previousCount() const { return previous_; }
  /// The BLAS's thread count now, as a guard finds it: 0 where the process has no OpenBLAS
  /// or the guard cannot reach it (then guards change nothing).
  static int currentCount() {
    int (*get)() = nullptr;
    symbol("openblas_get_num_threads", get);
    return get != nullptr ? get() : 0;
  }
  ScopedBlasThreads(const ScopedBlasThreads&) = delete;
  ScopedBlasThreads& operator=(const ScopedBlasThreads&) = delete;

  /// The BLAS runs on min(threads, previous count) threads (at least 1) until the next
  /// allow() or hold(); the destructor gives the previous count back.
  void allow(int threads) {
    const int count = std::max(1, std::min(threads, previous_));
    if (set_ == nullptr || count == current_) return;  // nothing to change
    set_(count);
    current_ = count;
  }
  /// true: the BLAS runs on at most the constructor's count (as after construction);
  /// false: on its previous count again, until the next hold(true).
  void hold(bool held) { allow(held ? threads_ : previous_); }

 private:
  // A function of the process's libraries by name, or null (copied from dlsym's object
  // pointer, which ISO C++ does not convert to a function pointer directly).
  template <class Function>
  static void symbol(const char* name, Function& function) {
    void* address = loadedSymbol(name);
    function = nullptr;
    if (address != nullptr) std::memcpy(&function, &address, sizeof(function));
  }
  // The global scope first (a program linked with the BLAS); then every loaded object by
  // name, since a library loaded into a local scope is not in the global one: the Python
  // module and its BLAS, loaded with RTLD_LOCAL, where a global lookup found no OpenBLAS and
  // the guard did nothing, so that a run from Python factored on another thread count than
  // the same run of offlineSimulator and their results differed in the last bits.
  static void* loadedSymbol(const char* name) {
    if (void* address = ::dlsym(RTLD_DEFAULT, name)) return address;
    struct Search {
      const char* name;
      void* address;
    } search{name, nullptr};
    ::dl_iterate_phdr(
        [](dl_phdr_info* info, std::size_t, void* data) -> int {
          auto* s = static_cast<Search*>(data);
          if (info->dlpi_name == nullptr || info->dlpi_name[0] == '\0') return 0;
          void* handle = ::dlopen(info->dlpi_name, RTLD_LAZY | RTLD_NOLOAD);  // no new load, a reference
          if (handle == nullptr) return 0;
          s->address = ::dlsym(handle, s->name);
          ::dlclose(handle);  // the object stays: it was loaded before this reference
          return s->address != nullptr ? 1 : 0;
        },
        &search);
    return search.address;
  }

  void (*set_)(int) = nullptr;
  int threads_ = 1;
  int previous_ = 0;
  int current_ = 0;  // the count this guard last set (previous_ until it sets one)
};

}  // namespace asyncfem
