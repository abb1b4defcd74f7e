// SPDX-License-Identifier: BSD-3-Clause
// The asyncfem Python module: NumPy and SciPy in and out, the GIL released inside the
// long C++ calls (assembly, factorization, stepping).

#include <bindings.hpp>

PYBIND11_MODULE(_asyncfem, module) {
  namespace python = asyncfem::python;
  module.doc() =
      "AsyncFEM: tetrahedral FEM meshes, matrices, sparse solvers, force models, single-rate and "
      "asynchronous implicit integrators, simulation output and off-screen rendering.\n\n"
      "Vectors are stacked 3n float64 arrays (x0 y0 z0 x1 ...), system matrices "
      "scipy.sparse.csc_matrix, positions (n, 3) arrays, ids 0-based.";
  module.attr("__version__") = ASYNCFEM_VERSION_STRING;
  module.attr("has_render") = static_cast<bool>(ASYNCFEM_PYTHON_WITH_RENDER);
  python::bindErrors(module);
  python::bindMesh(module);
  python::bindMatrices(module);
  python::bindSolvers(module);
  python::bindForceModels(module);
  python::bindIntegrators(module);
  python::bindAsync(module);
  python::bindModal(module);  // after bindAsync: adds RegionProposal.as_dict
  python::bindOutput(module);
#if ASYNCFEM_PYTHON_WITH_RENDER
  python::bindRender(module);
#endif
  python::bindContact(module);  // before bindScene: Problem takes a PenaltyContact
  python::bindScene(module);
}
