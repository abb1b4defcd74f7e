// SPDX-License-Identifier: BSD-3-Clause
// libraries/forceModel and libraries/corotationalLinearFEM, and force models written in
// Python (a pybind11 trampoline: slow, one Python call per evaluation, for prototyping).

#include <asyncfem/corotationalLinearFEM/corotationalLinearFEM.hpp>
#include <asyncfem/forceModel/linearForceModel.hpp>
#include <forceModels.hpp>

namespace asyncfem::python {

namespace {

using Sparse = Eigen::SparseMatrix<double>;

py::function requiredOverride(const ForceModel* model, const char* name) {
  py::function override = py::get_override(model, name);
  if (!override) {
    throw py::type_error(std::string("asyncfem.ForceModel subclass does not implement ") + name + "()");
  }
  return override;
}

Eigen::VectorXd copyVector(const Eigen::VectorXd& vector) { return vector; }

void readForces(const py::object& result, const char* method, Eigen::Index size, Eigen::VectorXd& forces) {
  const std::string name = std::string(method) + "() return value";
  forces = toVector(result, name.c_str(), size);
}

void readStiffness(const py::object& result, const char* method, Eigen::Index size, Sparse& stiffness) {
  Sparse matrix;
  try {
    matrix = result.cast<Sparse>();
  } catch (const py::cast_error&) {
    throw py::value_error(std::string(method) + "() return value: expected a scipy.sparse matrix");
  }
  if (matrix.rows() != size || matrix.cols() != size) {
    throw py::value_error(std::string(method) + "() return value: expected shape (" + std::to_string(size) + ", " +
                          std::to_string(size) + "), got (" + std::to_string(matrix.rows()) + ", " +
                          std::to_string(matrix.cols()) + ")");
  }
  stiffness = std::move(matrix);
}

}  // namespace

int PythonForceModel::numDofs() const {
  py::gil_scoped_acquire gil;
  return requiredOverride(this, "num_dofs")().cast<int>();
}

bool PythonForceModel::isLinear() const {
  py::gil_scoped_acquire gil;
  py::function override = py::get_override(this, "is_linear");
  return override ? override().cast<bool>() : false;
}

Sparse PythonForceModel::createStiffnessMatrix() const {
  py::gil_scoped_acquire gil;
  Sparse matrix;
  readStiffness(requiredOverride(this, "create_stiffness_matrix")(), "create_stiffness_matrix", numDofs(), matrix);
  return matrix;
}

void PythonForceModel::internalForces(const Eigen::VectorXd& displacement, Eigen::VectorXd& forces) {
  py::gil_scoped_acquire gil;
  // u is passed as a copy: the Python method may keep it.
  readForces(requiredOverride(this, "internal_forces")(copyVector(displacement)), "internal_forces",
             displacement.size(), forces);
}

void PythonForceModel::tangentStiffness(const Eigen::VectorXd& displacement, Sparse& stiffness) {
  py::gil_scoped_acquire gil;
  readStiffness(requiredOverride(this, "tangent_stiffness")(copyVector(displacement)), "tangent_stiffness",
                displacement.size(), stiffness);
}

void PythonForceModel::forcesAndTangent(const Eigen::VectorXd& displacement, Eigen::VectorXd& forces,
                                        Sparse& stiffness) {
  py::gil_scoped_acquire gil;
  py::function override = py::get_override(this, "forces_and_tangent");
  if (!override) {
    internalForces(displacement, forces);
    tangentStiffness(displacement, stiffness);
    return;
  }
  const py::object result = override(copyVector(displacement));
  if (!py::isinstance<py::tuple>(result) || py::len(result) != 2) {
    throw py::value_error("forces_and_tangent() return value: expected a tuple (forces, stiffness)");
  }
  const auto pair = result.cast<py::tuple>();
  readForces(pair[0], "forces_and_tangent", displacement.size(), forces);
  readStiffness(pair[1], "forces_and_tangent", displacement.size(), stiffness);
}

double PythonForceModel::elasticEnergy(const Eigen::VectorXd& displacement) {
  py::gil_scoped_acquire gil;
  py::function override = py::get_override(this, "elastic_energy");
  return override ? override(copyVector(displacement)).cast<double>() : 0.0;
}

std::shared_ptr<ForceModel> forceModelFromPython(const py::object& model) {
  auto pointer = model.cast<std::shared_ptr<ForceModel>>();
  if (dynamic_cast<PythonForceModel*>(pointer.get()) == nullptr) return pointer;
  // Aliasing shared_ptr: owns the C++ holder and a reference to the Python object (whose
  // __dict__ and overrides must outlive every C++ user), points at the model.
  struct Keeper {
    Keeper(std::shared_ptr<ForceModel> held, py::object object)
        : model(std::move(held)), reference(std::move(object)) {}
    std::shared_ptr<ForceModel> model;
    PythonReference reference;
  };
  auto keeper = std::make_shared<Keeper>(pointer, model);
  return {keeper, pointer.get()};
}

void bindForceModels(py::module_& module) {
  py::class_<ForceModel, PythonForceModel, std::shared_ptr<ForceModel>>(
      module, "ForceModel",
      "Internal elastic forces f_int(u) (they oppose the deformation: M a + D v + f_int(u) = f_ext).\n\n"
      "Subclass it in Python to prototype a force model the integrators can use: implement num_dofs(), "
      "create_stiffness_matrix() (the csc pattern every tangent has), internal_forces(u) -> (3n,), "
      "tangent_stiffness(u) -> csc_matrix with that pattern, and optionally is_linear(), "
      "forces_and_tangent(u) -> (f, K), elastic_energy(u). Call ForceModel.__init__(self) first. Every "
      "evaluation is a Python call that converts u, f and K: slow, for prototyping only.")
      .def(py::init_alias<>())
      .def("num_dofs", &ForceModel::numDofs, "3n, the length of u and f")
      .def("is_linear", &ForceModel::isLinear, "True when the tangent does not depend on u")
      .def("create_stiffness_matrix", &ForceModel::createStiffnessMatrix,
           "a csc_matrix with the pattern every tangent has (values zero)")
      .def(
          "internal_forces",
          [](ForceModel& model, const py::handle& u) {
            const Eigen::VectorXd displacement = toVector(u, "displacement", model.numDofs());
            Eigen::VectorXd forces;
            py::gil_scoped_release release;
            model.internalForces(displacement, forces);
            return forces;
          },
          py::arg("displacement"), "f_int(u), shape (3n,)")
      .def(
          "tangent_stiffness",
          [](ForceModel& model, const py::handle& u) {
            const Eigen::VectorXd displacement = toVector(u, "displacement", model.numDofs());
            py::gil_scoped_release release;
            Sparse stiffness = model.createStiffnessMatrix();
            model.tangentStiffness(displacement, stiffness);
            return stiffness;
          },
          py::arg("displacement"), "K(u) = d f_int / d u (csc_matrix)")
      .def(
          "forces_and_tangent",
          [](ForceModel& model, const py::handle& u) {
            const Eigen::VectorXd displacement = toVector(u, "displacement", model.numDofs());
            Eigen::VectorXd forces;
            Sparse stiffness;
            {
              py::gil_scoped_release release;
              stiffness = model.createStiffnessMatrix();
              model.forcesAndTangent(displacement, forces, stiffness);
            }
            return py::make_tuple(forces, stiffness);
          },
          py::arg("displacement"), "(f_int(u), K(u))")
      .def(
          "elastic_energy",
          [](ForceModel& model, const py::handle& u) {
            const Eigen::VectorXd displacement = toVector(u, "displacement", model.numDofs());
            py::gil_scoped_release release;
            return model.elasticEnergy(displacement);
          },
          py::arg("displacement"), "the elastic energy at displacement u")
      .def(
          "element_tangent",
          [](const ForceModel& model, const py::handle& u, int element) -> py::object {
            const Eigen::VectorXd displacement = toVector(u, "displacement", model.numDofs());
            Eigen::Matrix<double, 12, 12> tangent;
            bool available = false;
            {
              py::gil_scoped_release release;
              available = model.elementTangent(displacement, element, tangent);
            }
            if (!available) return py::none();
            return py::cast(tangent);
          },
          py::arg("displacement"), py::arg("element"),
          "12 x 12 tangent of one element, or None when the model has no per-element form");

  py::class_<LinearForceModel, ForceModel, std::shared_ptr<LinearForceModel>>(module, "LinearForceModel",
                                                                              "f_int(u) = K u with a constant K")
      .def(py::init<Sparse>(), py::arg("stiffness"))
      .def_property_readonly("stiffness", &LinearForceModel::stiffness);

  py::enum_<TangentKind>(module, "TangentKind",
                         "Corotational tangent: simple (R K0 R^T) or exact (with the rotation's derivative)")
      .value("simple", TangentKind::simple)
      .value("exact", TangentKind::exact);
  py::class_<CorotationalLinearFEM, ForceModel, std::shared_ptr<CorotationalLinearFEM>>(
      module, "CorotationalLinearFEM", "Corotated linear FEM (Mueller & Gross 2004) with the simple or exact tangent")
      .def(py::init<const TetMesh&, TangentKind>(), py::arg("mesh"), py::arg("tangent_kind") = TangentKind::simple,
           py::call_guard<py::gil_scoped_release>())
      .def(py::init([](const TetMesh& mesh, std::shared_ptr<MatrixAssembler> assembler, TangentKind kind) {
             py::gil_scoped_release release;
             return std::make_shared<CorotationalLinearFEM>(mesh, std::move(assembler), kind);
           }),
           py::arg("mesh"), py::arg("assembler"), py::arg("tangent_kind") = TangentKind::simple,
           "sharing an assembler (e.g. the mass matrix's), so all matrices have one pattern")
      .def_property_readonly("num_elements", &CorotationalLinearFEM::numElements)
      .def_property("tangent_kind", &CorotationalLinearFEM::tangentKind, &CorotationalLinearFEM::setTangentKind)
      .def_property_readonly(
          "rotations",
          [](const CorotationalLinearFEM& model) {
            const auto& rotations = model.rotations();
            py::array_t<double> result({static_cast<py::ssize_t>(rotations.size()), py::ssize_t{3}, py::ssize_t{3}});
            auto view = result.mutable_unchecked<3>();
            for (std::size_t e = 0; e < rotations.size(); ++e) {
              for (int i = 0; i < 3; ++i) {
                for (int j = 0; j < 3; ++j) view(static_cast<py::ssize_t>(e), i, j) = rotations[e](i, j);
              }
            }
            return result;
          },
          "(m, 3, 3) element rotations of the last evaluation")
      .def(
          "element_stiffness",
          [](const CorotationalLinearFEM& model, int e) {
            checkIndex(e, model.numElements(), "element");
            return ElementMatrix(model.elementStiffness(e));
          },
          py::arg("element"), "cached 12 x 12 linear K_e")
      .def_property_readonly("assembler", [](const CorotationalLinearFEM& model) {
        return std::const_pointer_cast<MatrixAssembler>(model.sharedAssembler());
      });
}

}  // namespace asyncfem::python
