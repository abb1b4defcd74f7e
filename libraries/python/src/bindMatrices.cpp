// SPDX-License-Identifier: BSD-3-Clause
// libraries/stiffnessMatrix: assembler, stiffness, mass, damping, element matrices,
// free-DOF extraction. Matrices go out as scipy.sparse.csc_matrix (pybind11 copies them).

#include <asyncfem/stiffnessMatrix/assembler.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <asyncfem/stiffnessMatrix/elementMatrices.hpp>
#include <bindings.hpp>

namespace asyncfem::python {

namespace {

using Sparse = Eigen::SparseMatrix<double>;
using Release = py::call_guard<py::gil_scoped_release>;

void checkAssembler(const TetMesh& mesh, const MatrixAssembler& assembler) {
  if (assembler.numDofs() != mesh.numDofs() || assembler.numElements() != mesh.numElements()) {
    throw py::value_error("assembler: built for " + std::to_string(assembler.numDofs()) + " DOFs and " +
                          std::to_string(assembler.numElements()) + " elements, the mesh has " +
                          std::to_string(mesh.numDofs()) + " and " + std::to_string(mesh.numElements()));
  }
}

}  // namespace

void bindMatrices(py::module_& module) {
  py::enum_<MassType>(module, "MassType", "Mass matrix: consistent (the FEM integral) or lumped (diagonal)")
      .value("consistent", MassType::consistent)
      .value("lumped", MassType::lumped);

  py::class_<MatrixAssembler, std::shared_ptr<MatrixAssembler>>(
      module, "MatrixAssembler",
      "Sparsity pattern of a mesh's 3n x 3n matrices and the element -> value slot map, built once; "
      "matrices from one assembler share their pattern.")
      .def(py::init<const TetMesh&>(), py::arg("mesh"), Release())
      .def_property_readonly("num_dofs", &MatrixAssembler::numDofs)
      .def_property_readonly("num_elements", &MatrixAssembler::numElements)
      .def_property_readonly("non_zeros", &MatrixAssembler::nonZeros)
      .def_property_readonly("num_colors", &MatrixAssembler::numColors)
      .def_property_readonly("elements_per_chunk", &MatrixAssembler::elementsPerChunk)
      .def("create_matrix", &MatrixAssembler::createMatrix, "the pattern with zero values (csc_matrix)")
      .def(
          "slot",
          [](const MatrixAssembler& assembler, int e, int i, int j) {
            checkIndex(e, assembler.numElements(), "element");
            checkIndex(i, 12, "local row");
            checkIndex(j, 12, "local column");
            return assembler.slot(e, i, j);
          },
          py::arg("element"), py::arg("i"), py::arg("j"),
          "index into the csc data array of entry (i, j) of element e's 12 x 12 matrix");

  module.def(
      "linear_stiffness_matrix",
      [](const TetMesh& mesh, const MatrixAssembler& assembler) {
        checkAssembler(mesh, assembler);
        py::gil_scoped_release release;
        return linearStiffnessMatrix(mesh, assembler);
      },
      py::arg("mesh"), py::arg("assembler"), "linear FEM stiffness K (3n x 3n csc_matrix)");
  module.def(
      "mass_matrix",
      [](const TetMesh& mesh, const MatrixAssembler& assembler, MassType type) {
        checkAssembler(mesh, assembler);
        py::gil_scoped_release release;
        return massMatrix(mesh, assembler, type);
      },
      py::arg("mesh"), py::arg("assembler"), py::arg("type") = MassType::consistent,
      "mass matrix M (3n x 3n csc_matrix), consistent or lumped");
  module.def("rayleigh_damping", &rayleighDamping, py::arg("mass"), py::arg("stiffness"), py::arg("alpha"),
             py::arg("beta"), Release(), "D = alpha M + beta K (same pattern)");
  module.def(
      "combine",
      [](const std::vector<double>& coefficients, const std::vector<Sparse>& matrices) {
        if (coefficients.size() != matrices.size()) {
          throw py::value_error("coefficients: " + std::to_string(coefficients.size()) + " given for " +
                                std::to_string(matrices.size()) + " matrices");
        }
        std::vector<const Sparse*> pointers;
        for (const Sparse& matrix : matrices) pointers.push_back(&matrix);
        Sparse out;
        py::gil_scoped_release release;
        combine(coefficients, pointers, out);
        return out;
      },
      py::arg("coefficients"), py::arg("matrices"), "sum_i c_i A_i of matrices sharing one pattern");

  module.def("lame_parameters", &lameParameters, py::arg("youngs_modulus"), py::arg("poisson_ratio"), "(lambda, mu)");
  module.def(
      "shape_function_gradients",
      [](const ElementPositions& rest) {
        double volume = 0.0;
        Eigen::Matrix<double, 3, 4> gradients = shapeFunctionGradients(rest, &volume);
        return py::make_tuple(gradients, volume);
      },
      py::arg("rest_positions"), "(3 x 4 gradients, signed volume) of a tet with vertex columns rest_positions");
  module.def("linear_element_stiffness", &linearElementStiffness, py::arg("rest_positions"), py::arg("youngs_modulus"),
             py::arg("poisson_ratio"), "12 x 12 V B^T C B");
  module.def("consistent_element_mass", &consistentElementMass, py::arg("volume"), py::arg("density"),
             "12 x 12 consistent mass matrix of a tet of this volume and density");
  module.def("lumped_element_mass", &lumpedElementMass, py::arg("volume"), py::arg("density"),
             "12 x 12 lumped (diagonal) mass matrix of a tet of this volume and density");

  py::class_<FreeDofs>(module, "FreeDofs", "Split of the 3n DOFs into fixed and free ones")
      .def(py::init([](int numDofs, const py::handle& fixed) {
             return FreeDofs(numDofs, indexListArgument(fixed, "fixed_dofs"));
           }),
           py::arg("num_dofs"), py::arg("fixed_dofs"))
      .def_static(
          "from_fixed_vertices",
          [](int numVertices, const py::handle& vertices) {
            return FreeDofs::fromFixedVertices(numVertices, indexListArgument(vertices, "fixed_vertices"));
          },
          py::arg("num_vertices"), py::arg("fixed_vertices"))
      .def_property_readonly("num_dofs", &FreeDofs::numDofs)
      .def_property_readonly("num_free", &FreeDofs::numFree)
      .def_property_readonly("num_fixed", &FreeDofs::numFixed)
      .def_property_readonly("free_to_full", [](const FreeDofs& dofs) { return intArray(dofs.freeToFull()); })
      .def_property_readonly("full_to_free", [](const FreeDofs& dofs) { return intArray(dofs.fullToFree()); })
      .def(
          "is_fixed",
          [](const FreeDofs& dofs, int dof) {
            checkIndex(dof, dofs.numDofs(), "DOF");
            return dofs.isFixed(dof);
          },
          py::arg("dof"), "whether a DOF (0 to 3n - 1) is fixed")
      .def(
          "restrict",
          [](const FreeDofs& dofs, const py::handle& full) {
            return dofs.restrict(toVector(full, "full", dofs.numDofs()));
          },
          py::arg("full"), "the free entries of a 3n vector")
      .def(
          "expand",
          [](const FreeDofs& dofs, const py::handle& free) {
            return dofs.expand(toVector(free, "free", dofs.numFree()));
          },
          py::arg("free"), "a 3n vector with the free entries given and the fixed ones zero")
      .def(
          "free_matrix",
          [](const FreeDofs& dofs, const Sparse& full) {
            if (full.rows() != dofs.numDofs() || full.cols() != dofs.numDofs()) {
              throw py::value_error("matrix: expected shape (" + std::to_string(dofs.numDofs()) + ", " +
                                    std::to_string(dofs.numDofs()) + "), got (" + std::to_string(full.rows()) + ", " +
                                    std::to_string(full.cols()) + ")");
            }
            py::gil_scoped_release release;
            return SubmatrixExtractor(full, dofs.freeToFull(), dofs.freeToFull()).extract(full);
          },
          py::arg("matrix"), "the free rows and columns of a 3n x 3n matrix");

  py::class_<SubmatrixExtractor>(module, "SubmatrixExtractor",
                                 "A(rows, cols) of a sparse matrix, pattern and value map built once")
      .def(py::init([](const Sparse& full, const py::handle& rows, const py::handle& columns) {
             return SubmatrixExtractor(full, indexListArgument(rows, "rows"), indexListArgument(columns, "cols"));
           }),
           py::arg("full"), py::arg("rows"), py::arg("cols"))
      .def("extract", &SubmatrixExtractor::extract, py::arg("full"), Release(),
           "the submatrix of full (which must have the pattern the extractor was built from)")
      .def(
          "update",
          [](const SubmatrixExtractor& extractor, const Sparse& full, Sparse sub) {
            py::gil_scoped_release release;
            extractor.update(full, sub);
            return sub;
          },
          py::arg("full"), py::arg("sub"), "sub's pattern with the values of full (a new matrix)");
}

}  // namespace asyncfem::python
