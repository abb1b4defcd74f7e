// SPDX-License-Identifier: BSD-3-Clause
#include "detail/petscCall.hpp"

#include <asyncfem/core/error.hpp>
#include <exception>
#include <string>

namespace asyncfem::detail {

namespace {

// The first message of the error being unwound (PETSc calls the handler once per frame
// of its call stack; the innermost frame, PETSC_ERROR_INITIAL, has the real message).
thread_local std::string lastPetscMessage;

PetscErrorCode recordingErrorHandler(MPI_Comm /*comm*/, int line, const char* function, const char* file,
                                     PetscErrorCode code, PetscErrorType type, const char* message, void* /*context*/) {
  if (type == PETSC_ERROR_INITIAL) {
    const char* generic = nullptr;
    PetscErrorMessage(code, &generic, nullptr);
    lastPetscMessage = std::string(message != nullptr && *message != '\0' ? message : (generic ? generic : "error")) +
                       " (in " + (function ? function : "?") + ", " + (file ? file : "?") + ":" + std::to_string(line) +
                       ")";
  }
  return code;
}

enum class FailureKind : int { none = 0, error = 1, validation = 2, numerical = 3 };

}  // namespace

void installPetscErrorHandler() {
  static thread_local bool installed = false;
  if (installed) return;
  PetscPushErrorHandler(recordingErrorHandler, nullptr);
  installed = true;
}

void checkPetsc(PetscErrorCode code, const char* call) {
  if (code == 0) return;
  std::string message =
      lastPetscMessage.empty() ? "error code " + std::to_string(static_cast<int>(code)) : lastPetscMessage;
  lastPetscMessage.clear();
  throw Error(std::string("PETSc: ") + call + " failed: " + message);
}

void collectively(MPI_Comm comm, const std::function<void()>& work) {
  int rank = 0;
  int size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  FailureKind kind = FailureKind::none;
  std::string message;
  try {
    work();
  } catch (const ValidationError& error) {
    kind = FailureKind::validation;
    message = error.what();
  } catch (const NumericalError& error) {
    kind = FailureKind::numerical;
    message = error.what();
  } catch (const std::exception& error) {
    kind = FailureKind::error;
    message = error.what();
  }
  const int candidate = kind == FailureKind::none ? size : rank;
  int failingRank = size;
  MPI_Allreduce(&candidate, &failingRank, 1, MPI_INT, MPI_MIN, comm);
  if (failingRank == size) return;

  int header[2] = {static_cast<int>(kind), static_cast<int>(message.size())};
  MPI_Bcast(header, 2, MPI_INT, failingRank, comm);
  message.resize(static_cast<std::size_t>(header[1]));
  MPI_Bcast(message.data(), header[1], MPI_CHAR, failingRank, comm);
  const std::string text = "rank " + std::to_string(failingRank) + ": " + message;
  switch (static_cast<FailureKind>(header[0])) {
    case FailureKind::validation:
      throw ValidationError(text);
    case FailureKind::numerical:
      throw NumericalError(text);
    default:
      throw Error(text);
  }
}

void sumOverRanks(MPI_Comm comm, double* values, std::size_t count) {
  if (count == 0) return;
  if (MPI_Allreduce(MPI_IN_PLACE, values, static_cast<int>(count), MPI_DOUBLE, MPI_SUM, comm) != MPI_SUCCESS) {
    throw Error("MPI_Allreduce (a sum over the ranks) failed");
  }
}

}  // namespace asyncfem::detail
