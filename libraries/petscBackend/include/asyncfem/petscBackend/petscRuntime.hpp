// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <string>

namespace asyncfem {

/// Scope of PETSc (and MPI) in a program: the constructor initializes PETSc on
/// MPI_COMM_WORLD unless it already is, the destructor finalizes it if this object
/// initialized it. Create exactly one, in main(), before any other backend object, and
/// let it outlive them all.
///
/// PETSc errors are turned into asyncfem::Error exceptions (PETSc's message, the failing
/// routine and its source line); PETSc prints nothing itself. Every backend object is
/// collective: all ranks construct and call it in the same order.
class PetscRuntime {
 public:
  /// argc, argv: the program's, so that PETSc options given on the command line
  /// (-ksp_type, -pc_type, -log_view, ...) enter PETSc's options database; they may be
  /// nullptr. options: more options in the same syntax ("-ksp_monitor -pc_type jacobi"),
  /// inserted after the command line. Throws asyncfem::Error if PETSc fails to start.
  PetscRuntime(int* argc, char*** argv, const std::string& options = "");
  ~PetscRuntime();
  PetscRuntime(const PetscRuntime&) = delete;
  PetscRuntime& operator=(const PetscRuntime&) = delete;

  /// This process's rank in MPI_COMM_WORLD and the number of ranks.
  int rank() const { return rank_; }
  int size() const { return size_; }
  /// The largest of value over the ranks, on every rank (collective: every rank calls it),
  /// e.g. so that a stop request one rank received stops all of them at the same point.
  int maxOverRanks(int value) const;

 private:
  bool ownsInitialization_ = false;
  int rank_ = 0;
  int size_ = 1;
};

}  // namespace asyncfem
