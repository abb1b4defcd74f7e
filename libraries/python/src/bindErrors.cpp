// SPDX-License-Identifier: BSD-3-Clause
// asyncfem::Error and its subclasses as Python exceptions carrying their fields.

#include <asyncfem/core/error.hpp>
#include <bindings.hpp>

namespace asyncfem::python {

namespace {

// The exception types live as long as the module (never unloaded), so plain handles
// with one owned reference each are enough.
PyObject* errorType = nullptr;
PyObject* parseErrorType = nullptr;
PyObject* validationErrorType = nullptr;
PyObject* numericalErrorType = nullptr;

PyObject* newType(py::module_& module, const char* name, PyObject* base, const char* doc) {
  const std::string qualified = std::string("asyncfem.") + name;
  PyObject* type = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, base, nullptr);
  if (type == nullptr) throw py::error_already_set();
  module.add_object(name, py::reinterpret_borrow<py::object>(type));
  return type;
}

// Raises type(message) with the attribute message (and the extra fields already set).
void raise(PyObject* type, const std::string& message, const py::dict& fields = {}) {
  py::object instance = py::reinterpret_borrow<py::object>(type)(message);
  instance.attr("message") = message;
  for (const auto& [key, value] : fields) instance.attr(key) = value;
  PyErr_SetObject(type, instance.ptr());
}

}  // namespace

void bindErrors(py::module_& module) {
  errorType = newType(module, "Error", PyExc_RuntimeError,
                      "Base of every error AsyncFEM raises; str(e) and e.message name the file and line, the "
                      "element or vertex, or the scene key.");
  parseErrorType = newType(module, "ParseError", errorType,
                           "Malformed input file: e.file is the file, e.line the 1-based line (0: the whole file).");
  validationErrorType = newType(module, "ValidationError", errorType,
                                "Input that parses but is not valid (degenerate element, unknown set, bad value).");
  numericalErrorType =
      newType(module, "NumericalError", errorType,
              "A computation failed numerically (non-finite state, failed factorization). Where it happened, "
              "when known: e.frame (0-based), e.step (1-based), e.time, e.dof, e.vertex (0-based; -1 or nan when "
              "unknown) and e.region, e.region_name (multirate integrators; -1: the large-step region L).");
  py::register_exception_translator([](std::exception_ptr pointer) {
    try {
      if (pointer) std::rethrow_exception(pointer);
    } catch (const ParseError& error) {
      py::dict fields;
      fields["file"] = error.file();
      fields["line"] = error.line();
      raise(parseErrorType, error.what(), fields);
    } catch (const ValidationError& error) {
      raise(validationErrorType, error.what());
    } catch (const NumericalError& error) {
      const NumericalErrorLocation& where = error.location();
      py::dict fields;
      fields["frame"] = where.frame;
      fields["step"] = where.step;
      fields["time"] = where.time;
      fields["dof"] = where.dof;
      fields["vertex"] = where.vertex;
      fields["region"] = where.region;
      fields["region_name"] = where.regionName;
      raise(numericalErrorType, error.what(), fields);
    } catch (const Error& error) {
      raise(errorType, error.what());
    }
  });
}

}  // namespace asyncfem::python
