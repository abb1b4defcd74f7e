// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <petscksp.h>
#include <petscmat.h>
#include <petscvec.h>

namespace asyncfem::detail {

/// Owner of one PETSc object (Mat, Vec, KSP, ...): destroys it with destroy() when it
/// goes out of scope. Move-only.
template <class Object, PetscErrorCode (*destroy)(Object*)>
class PetscHandle {
 public:
  PetscHandle() = default;
  ~PetscHandle() { reset(); }
  PetscHandle(const PetscHandle&) = delete;
  PetscHandle& operator=(const PetscHandle&) = delete;
  PetscHandle(PetscHandle&& other) noexcept : object_(other.object_) { other.object_ = nullptr; }
  PetscHandle& operator=(PetscHandle&& other) noexcept {
    if (this != &other) {
      reset();
      object_ = other.object_;
      other.object_ = nullptr;
    }
    return *this;
  }

  Object get() const { return object_; }
  /// For PETSc's creation functions (MatCreate(comm, handle.out())); destroys what was held.
  Object* out() {
    reset();
    return &object_;
  }
  void reset() {
    if (object_ != nullptr) destroy(&object_);
    object_ = nullptr;
  }

 private:
  Object object_ = nullptr;
};

using MatHandle = PetscHandle<Mat, MatDestroy>;
using VecHandle = PetscHandle<Vec, VecDestroy>;
using KspHandle = PetscHandle<KSP, KSPDestroy>;
using ScatterHandle = PetscHandle<VecScatter, VecScatterDestroy>;
using NullSpaceHandle = PetscHandle<MatNullSpace, MatNullSpaceDestroy>;
using OptionsHandle = PetscHandle<PetscOptions, PetscOptionsDestroy>;

}  // namespace asyncfem::detail
