// SPDX-License-Identifier: BSD-3-Clause
#pragma once

// Shared by the binding files of the asyncfem Python module: one function per library
// that adds its classes and functions to the module, and the NumPy argument checks that
// turn a wrong shape or dtype into a ValueError naming the argument.

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>
#include <string>
#include <vector>

namespace asyncfem::python {

namespace py = pybind11;

void bindErrors(py::module_& module);
void bindMesh(py::module_& module);
void bindMatrices(py::module_& module);
void bindSolvers(py::module_& module);
void bindForceModels(py::module_& module);
void bindIntegrators(py::module_& module);
void bindAsync(py::module_& module);
void bindModal(py::module_& module);
void bindOutput(py::module_& module);
void bindRender(py::module_& module);
void bindScene(py::module_& module);
void bindContact(py::module_& module);

/// A float64 1-D array of `size` entries (any size when size < 0) taken from value without
/// a copy when it already is a contiguous float64 ndarray; other array-likes (lists) are
/// converted. Raises ValueError "NAME: expected ..." for an ndarray of another dtype, a
/// wrong shape or size, or something that is not numeric.
py::array_t<double> vectorArgument(const py::handle& value, const char* name, Eigen::Index size = -1);
/// Same for a float64 array of shape (rows, columns) (rows < 0: any number of rows), C order.
py::array_t<double> matrixArgument(const py::handle& value, const char* name, Eigen::Index rows, Eigen::Index columns);
/// An integer array of shape (rows, columns) (rows < 0: any), any integer dtype, copied to
/// int32 with a range check; a float array is a ValueError.
py::array_t<int> indexMatrixArgument(const py::handle& value, const char* name, Eigen::Index rows,
                                     Eigen::Index columns);
/// A list of ints from a 1-D integer array or a sequence of ints (ValueError otherwise).
std::vector<int> indexListArgument(const py::handle& value, const char* name);

/// Eigen views of checked arrays (the array must outlive the view).
inline Eigen::Map<const Eigen::VectorXd> asVector(const py::array_t<double>& array) {
  return {array.data(), static_cast<Eigen::Index>(array.size())};
}
using RowMatrixXd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
inline Eigen::Map<const RowMatrixXd> asRowMatrix(const py::array_t<double>& array) {
  return {array.data(), static_cast<Eigen::Index>(array.shape(0)), static_cast<Eigen::Index>(array.shape(1))};
}
/// A copy as Eigen::VectorXd (for C++ functions that take const VectorXd&).
Eigen::VectorXd toVector(const py::handle& value, const char* name, Eigen::Index size = -1);

/// Read-only NumPy view of data owned by owner (kept alive by the array): no copy.
py::array readOnlyVectorView(const Eigen::VectorXd& vector, const py::handle& owner);
/// (columns, rows) read-only view of a column-major rows x columns matrix (e.g. 3 x n
/// positions seen as n x 3), no copy.
template <class Scalar, int Rows>
py::array transposedView(const Eigen::Matrix<Scalar, Rows, Eigen::Dynamic>& matrix, const py::handle& owner) {
  const auto size = static_cast<py::ssize_t>(sizeof(Scalar));
  py::array result(py::dtype::of<Scalar>(), {static_cast<py::ssize_t>(matrix.cols()), static_cast<py::ssize_t>(Rows)},
                   {size * Rows, size}, matrix.data(), owner);
  py::detail::array_proxy(result.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return result;
}
/// A new int32 array holding the values (a copy).
py::array_t<int> intArray(const std::vector<int>& values);
/// A new (count, 3) int32 array of triangles.
template <class Triangles>
py::array_t<int> triangleArray(const Triangles& triangles) {
  py::array_t<int> result({static_cast<py::ssize_t>(triangles.size()), static_cast<py::ssize_t>(3)});
  auto view = result.template mutable_unchecked<2>();
  for (std::size_t i = 0; i < triangles.size(); ++i) {
    for (int c = 0; c < 3; ++c) view(static_cast<py::ssize_t>(i), c) = triangles[i][static_cast<std::size_t>(c)];
  }
  return result;
}

/// An index in [0, count), else IndexError naming what it indexes.
void checkIndex(long long index, long long count, const char* what);

/// Holds a Python object on the C++ side (inside a std::function or a shared_ptr that C++
/// code may copy or destroy without holding the GIL): the reference is dropped under the
/// GIL.
class PythonReference {
 public:
  explicit PythonReference(py::object object) : object_(std::move(object)) {}
  ~PythonReference() {
    py::gil_scoped_acquire gil;
    object_ = py::object();
  }
  PythonReference(const PythonReference&) = delete;
  PythonReference& operator=(const PythonReference&) = delete;
  const py::object& get() const { return object_; }

 private:
  py::object object_;
};

}  // namespace asyncfem::python
