// SPDX-License-Identifier: BSD-3-Clause
// NumPy argument checks and views shared by every binding file.

#include <bindings.hpp>
#include <climits>
#include <string>

namespace asyncfem::python {

namespace {

std::string shapeString(const py::array& array) {
  std::string text = "(";
  for (py::ssize_t i = 0; i < array.ndim(); ++i) {
    if (i > 0) text += ", ";
    text += std::to_string(array.shape(i));
  }
  if (array.ndim() == 1) text += ",";
  return text + ")";
}

std::string expectedShape(Eigen::Index rows, Eigen::Index columns) {
  const std::string first = rows < 0 ? "n" : std::to_string(rows);
  return columns < 0 ? "(" + first + ",)" : "(" + first + ", " + std::to_string(columns) + ")";
}

std::string dtypeName(const py::array& array) { return py::str(array.dtype()).cast<std::string>(); }

// value as an ndarray: itself if it is one (dtype checked by the caller), else
// numpy.asarray(value) (so lists and tuples work).
py::array asArray(const py::handle& value, const char* name) {
  if (value.is_none()) {
    throw py::value_error(std::string(name) + ": expected an array, got None");
  }
  if (py::isinstance<py::array>(value)) return py::reinterpret_borrow<py::array>(value);
  try {
    return py::module_::import("numpy").attr("asarray")(value);
  } catch (py::error_already_set&) {
    throw py::value_error(std::string(name) + ": expected an array of numbers, got " +
                          py::str(py::type::handle_of(value).attr("__name__")).cast<std::string>());
  }
}

py::array floatArray(const py::handle& value, const char* name) {
  py::array array = asArray(value, name);
  const char kind = array.dtype().kind();
  if (py::isinstance<py::array>(value)) {
    // An ndarray keeps its dtype: converting float32 or int arrays silently would hide
    // a mistake (and a copy) from the caller.
    if (!array.dtype().is(py::dtype::of<double>())) {
      throw py::value_error(std::string(name) + ": expected dtype float64, got " + dtypeName(array));
    }
  } else if (kind != 'f' && kind != 'i' && kind != 'u') {
    throw py::value_error(std::string(name) + ": expected an array of numbers, got dtype " + dtypeName(array));
  }
  return array;
}

}  // namespace

py::array_t<double> vectorArgument(const py::handle& value, const char* name, Eigen::Index size) {
  const py::array array = floatArray(value, name);
  if (array.ndim() != 1 || (size >= 0 && array.shape(0) != size)) {
    throw py::value_error(std::string(name) + ": expected a float64 array of shape " + expectedShape(size, -1) +
                          ", got shape " + shapeString(array));
  }
  // No copy for a contiguous float64 array.
  return py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(array);
}

py::array_t<double> matrixArgument(const py::handle& value, const char* name, Eigen::Index rows, Eigen::Index columns) {
  const py::array array = floatArray(value, name);
  if (array.ndim() != 2 || (rows >= 0 && array.shape(0) != rows) || array.shape(1) != columns) {
    throw py::value_error(std::string(name) + ": expected a float64 array of shape " + expectedShape(rows, columns) +
                          ", got shape " + shapeString(array));
  }
  return py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(array);
}

py::array_t<int> indexMatrixArgument(const py::handle& value, const char* name, Eigen::Index rows,
                                     Eigen::Index columns) {
  const py::array array = asArray(value, name);
  const char kind = array.dtype().kind();
  if (kind != 'i' && kind != 'u') {
    throw py::value_error(std::string(name) + ": expected an integer array, got dtype " + dtypeName(array));
  }
  if (array.ndim() != 2 || (rows >= 0 && array.shape(0) != rows) || array.shape(1) != columns) {
    throw py::value_error(std::string(name) + ": expected an integer array of shape " + expectedShape(rows, columns) +
                          ", got shape " + shapeString(array));
  }
  const auto wide = py::array_t<long long, py::array::c_style | py::array::forcecast>::ensure(array);
  py::array_t<int> result({array.shape(0), array.shape(1)});
  const long long* source = wide.data();
  int* target = result.mutable_data();
  for (py::ssize_t i = 0; i < wide.size(); ++i) {
    if (source[i] < INT_MIN || source[i] > INT_MAX) {
      throw py::value_error(std::string(name) + ": value " + std::to_string(source[i]) + " does not fit in int32");
    }
    target[i] = static_cast<int>(source[i]);
  }
  return result;
}

std::vector<int> indexListArgument(const py::handle& value, const char* name) {
  const py::array array = asArray(value, name);
  if (array.size() == 0) return {};
  const char kind = array.dtype().kind();
  if ((kind != 'i' && kind != 'u') || array.ndim() != 1) {
    throw py::value_error(std::string(name) + ": expected a 1-D list or array of integers, got dtype " +
                          dtypeName(array) + " and shape " + shapeString(array));
  }
  const auto wide = py::array_t<long long, py::array::c_style | py::array::forcecast>::ensure(array);
  std::vector<int> result(static_cast<std::size_t>(wide.size()));
  for (py::ssize_t i = 0; i < wide.size(); ++i) {
    const long long v = wide.data()[i];
    if (v < INT_MIN || v > INT_MAX) {
      throw py::value_error(std::string(name) + ": value " + std::to_string(v) + " does not fit in int32");
    }
    result[static_cast<std::size_t>(i)] = static_cast<int>(v);
  }
  return result;
}

Eigen::VectorXd toVector(const py::handle& value, const char* name, Eigen::Index size) {
  return asVector(vectorArgument(value, name, size));
}

py::array readOnlyVectorView(const Eigen::VectorXd& vector, const py::handle& owner) {
  py::array result(py::dtype::of<double>(), {static_cast<py::ssize_t>(vector.size())},
                   {static_cast<py::ssize_t>(sizeof(double))}, vector.data(), owner);
  py::detail::array_proxy(result.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return result;
}

py::array_t<int> intArray(const std::vector<int>& values) {
  py::array_t<int> result(static_cast<py::ssize_t>(values.size()));
  std::copy(values.begin(), values.end(), result.mutable_data());
  return result;
}

void checkIndex(long long index, long long count, const char* what) {
  if (index < 0 || index >= count) {
    throw py::index_error(std::string(what) + " " + std::to_string(index) + " out of range [0, " +
                          std::to_string(count) + ")");
  }
}

}  // namespace asyncfem::python
