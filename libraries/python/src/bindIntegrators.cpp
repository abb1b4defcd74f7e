// SPDX-License-Identifier: BSD-3-Clause
// libraries/integrator: the dynamic system, the single-rate integrators, their options
// and statistics. step() releases the GIL; external forces and force models written in
// Python take it back for their calls.

#include <asyncfem/integrator/backwardEuler.hpp>
#include <asyncfem/integrator/centralDifferences.hpp>
#include <asyncfem/integrator/factory.hpp>
#include <asyncfem/integrator/stableTimestep.hpp>
#include <asyncfem/integrator/symplecticEuler.hpp>
#include <asyncfem/integrator/trapezoidal.hpp>
#include <forceModels.hpp>
#include <integrators.hpp>

namespace asyncfem::python {

namespace {

using Sparse = Eigen::SparseMatrix<double>;

// f_ext(t, u, v) from a Python callable returning a (3n,) array (added to the forces) or
// None (no force at that time).
ExternalForceFunction externalForceFromPython(const py::object& callable) {
  if (callable.is_none()) return {};
  if (!PyCallable_Check(callable.ptr())) {
    throw py::value_error("external_force: expected a callable f(time, displacement, velocity) -> (3n,) array");
  }
  auto function = std::make_shared<PythonReference>(callable);
  return [function](double time, const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity,
                    Eigen::VectorXd& forces) {
    py::gil_scoped_acquire gil;
    // u and v are copies: the callable may keep them.
    const py::object result = function->get()(time, Eigen::VectorXd(displacement), Eigen::VectorXd(velocity));
    if (result.is_none()) return;
    const auto values = vectorArgument(result, "external_force return value", forces.size());
    forces += asVector(values);
  };
}

void stepIntegrator(Integrator& integrator, int count) {
  if (count < 0) throw py::value_error("count: expected a count >= 0, got " + std::to_string(count));
  py::gil_scoped_release release;
  for (int k = 0; k < count; ++k) integrator.step();
}

template <class Concrete>
py::class_<Concrete, Integrator> singleRate(py::module_& module, const char* name, const char* doc) {
  return py::class_<Concrete, Integrator>(module, name, doc)
      .def(py::init([](const PythonDynamicSystem& system, double timestep, const IntegratorOptions& options) {
             DynamicSystem copy = checkedSystem(system);
             py::gil_scoped_release release;
             return std::make_unique<Concrete>(std::move(copy), timestep, options);
           }),
           py::arg("system"), py::arg("timestep"), py::arg("options") = IntegratorOptions{});
}

}  // namespace

DynamicSystem checkedSystem(const PythonDynamicSystem& given) {
  const DynamicSystem& system = given.system;
  if (!system.forceModel) throw py::value_error("system.force_model: not set");
  const int n = system.forceModel->numDofs();
  if (system.mass.rows() != n || system.mass.cols() != n) {
    throw py::value_error("system.mass: expected shape (" + std::to_string(n) + ", " + std::to_string(n) +
                          ") like the force model, got (" + std::to_string(system.mass.rows()) + ", " +
                          std::to_string(system.mass.cols()) + ")");
  }
  if (system.freeDofs.numDofs() != n) {
    throw py::value_error("system.free_dofs: built for " + std::to_string(system.freeDofs.numDofs()) +
                          " DOFs, the force model has " + std::to_string(n));
  }
  system.validate();
  return system;
}

void bindIntegrators(py::module_& module) {
  py::class_<PythonDynamicSystem>(module, "DynamicSystem",
                                  "M a + D v + f_int(u) = f_ext(t, u, v), D = alpha M + beta K, fixed DOFs removed")
      .def(py::init([](const py::object& forceModel, Sparse mass, FreeDofs freeDofs, double alpha, double beta,
                       const py::object& externalForce) {
             PythonDynamicSystem result;
             if (!forceModel.is_none()) result.system.forceModel = forceModelFromPython(forceModel);
             result.system.mass = std::move(mass);
             result.system.freeDofs = std::move(freeDofs);
             result.system.rayleighMass = alpha;
             result.system.rayleighStiffness = beta;
             result.system.externalForce = externalForceFromPython(externalForce);
             result.externalForce = externalForce;
             return result;
           }),
           py::arg("force_model") = py::none(), py::arg("mass") = Sparse(), py::arg("free_dofs") = FreeDofs(),
           py::arg("rayleigh_mass") = 0.0, py::arg("rayleigh_stiffness") = 0.0, py::arg("external_force") = py::none())
      .def_property(
          "force_model", [](const PythonDynamicSystem& s) { return s.system.forceModel; },
          [](PythonDynamicSystem& s, const py::object& model) { s.system.forceModel = forceModelFromPython(model); })
      .def_property(
          "mass", [](const PythonDynamicSystem& s) { return s.system.mass; },
          [](PythonDynamicSystem& s, Sparse mass) { s.system.mass = std::move(mass); })
      .def_property(
          "free_dofs", [](const PythonDynamicSystem& s) { return s.system.freeDofs; },
          [](PythonDynamicSystem& s, FreeDofs dofs) { s.system.freeDofs = std::move(dofs); })
      .def_property(
          "rayleigh_mass", [](const PythonDynamicSystem& s) { return s.system.rayleighMass; },
          [](PythonDynamicSystem& s, double alpha) { s.system.rayleighMass = alpha; }, "alpha (1/s)")
      .def_property(
          "rayleigh_stiffness", [](const PythonDynamicSystem& s) { return s.system.rayleighStiffness; },
          [](PythonDynamicSystem& s, double beta) { s.system.rayleighStiffness = beta; }, "beta (s)")
      .def_property(
          "external_force", [](const PythonDynamicSystem& s) { return s.externalForce; },
          [](PythonDynamicSystem& s, const py::object& callable) {
            s.system.externalForce = externalForceFromPython(callable);
            // A Python function may change at any time: no multirate integrator may take it
            // as constant over a large step (what a Problem's loads allowed).
            s.system.externalForceChanges = nullptr;
            s.system.externalForceAt = nullptr;
            s.system.externalForceOfRank = nullptr;
            s.system.stateDependentOnlyInContact = false;
            s.externalForce = callable;
          },
          "callable f(time, u, v) -> (3n,) array or None, added to the external force; one Python call per "
          "evaluation (slow for large meshes)")
      .def_property_readonly("num_dofs", [](const PythonDynamicSystem& s) { return s.system.numDofs(); })
      .def(
          "validate", [](const PythonDynamicSystem& s) { (void)checkedSystem(s); },
          "checks that the parts fit together (ValueError naming the field)");

  py::class_<IntegratorOptions>(
      module, "IntegratorOptions",
      "Options of the single-rate integrators: solver, Newton iterations and tolerance, line search, factor reuse")
      .def(py::init([](SolverKind solver, int maxIterations, double tolerance, double maxFrequency, bool force,
                       bool lineSearch, bool rayleighStiffnessAtIterate, bool reuseFactor, double pcgTolerance,
                       bool pcgSinglePrecision) {
             IntegratorOptions options;  // by name: the struct gains fields over time
             options.solver = solver;
             options.maxIterations = maxIterations;
             options.tolerance = tolerance;
             options.maxFrequency = maxFrequency;
             options.force = force;
             options.lineSearch = lineSearch;
             options.rayleighStiffnessAtIterate = rayleighStiffnessAtIterate;
             options.reuseFactor = reuseFactor;
             options.pcgTolerance = pcgTolerance;
             options.pcgSinglePrecision = pcgSinglePrecision;
             return options;
           }),
           py::arg("solver") = SolverKind::cholmod, py::arg("max_iterations") = 1, py::arg("tolerance") = 1e-8,
           py::arg("max_frequency") = 0.0, py::arg("force") = false, py::arg("line_search") = true,
           py::arg("rayleigh_stiffness_at_iterate") = false, py::arg("reuse_factor") = true,
           py::arg("pcg_tolerance") = 1e-10, py::arg("pcg_single_precision") = true)
      .def_readwrite("solver", &IntegratorOptions::solver)
      .def_readwrite("max_iterations", &IntegratorOptions::maxIterations)
      .def_readwrite("tolerance", &IntegratorOptions::tolerance)
      .def_readwrite("max_frequency", &IntegratorOptions::maxFrequency)
      .def_readwrite("line_search", &IntegratorOptions::lineSearch)
      .def_readwrite("rayleigh_stiffness_at_iterate", &IntegratorOptions::rayleighStiffnessAtIterate)
      .def_readwrite("reuse_factor", &IntegratorOptions::reuseFactor)
      .def_readwrite("pcg_tolerance", &IntegratorOptions::pcgTolerance)
      .def_readwrite("pcg_single_precision", &IntegratorOptions::pcgSinglePrecision)
      .def_readwrite("force", &IntegratorOptions::force);

  py::class_<IntegratorStats>(module, "IntegratorStats",
                              "Time and work of an integrator so far: seconds per phase, steps, factorizations, flops")
      .def_readonly("force_seconds", &IntegratorStats::forceSeconds)
      .def_readonly("assembly_seconds", &IntegratorStats::assemblySeconds)
      .def_readonly("factorization_seconds", &IntegratorStats::factorizationSeconds)
      .def_readonly("solve_seconds", &IntegratorStats::solveSeconds)
      .def_readonly("steps", &IntegratorStats::steps)
      .def_readonly("factorizations", &IntegratorStats::factorizations)
      .def_readonly("solved_right_hand_sides", &IntegratorStats::solvedRightHandSides)
      .def_readonly("factor_flops", &IntegratorStats::factorFlops)
      .def_readonly("solve_flops", &IntegratorStats::solveFlops)
      .def_readonly("skipped", &IntegratorStats::skipped);

  py::class_<Integrator>(module, "Integrator", "Owns the state (u, v, t) of a DynamicSystem and advances it")
      .def_property_readonly("name", &Integrator::name)
      .def("step", &stepIntegrator, py::arg("count") = 1,
           "advances by count steps (large steps for async), without the GIL")
      .def("stable_timestep_estimate", &Integrator::stableTimestepEstimate,
           "estimate of the largest stable timestep (infinity for unconditionally stable schemes)")
      .def(
          "set_state",
          [](Integrator& integrator, const py::handle& u, const py::handle& v, double time) {
            const Eigen::Index n = integrator.displacement().size();
            const Eigen::VectorXd displacement = toVector(u, "displacement", n);
            const Eigen::VectorXd velocity = toVector(v, "velocity", n);
            integrator.setState(displacement, velocity, time);
          },
          py::arg("displacement"), py::arg("velocity"), py::arg("time") = 0.0,
          "sets u, v (3n; fixed entries zeroed) and the time")
      .def("internal_state", &Integrator::internalState,
           "state beyond (u, v, t) needed to continue exactly (trapezoidal a_k; empty for most)")
      .def(
          "set_internal_state",
          [](Integrator& integrator, const py::handle& state) {
            integrator.setInternalState(toVector(state, "state"));
          },
          py::arg("state"), "restores internal_state() (with set_state) to continue a run exactly")
      .def_property_readonly(
          "displacement",
          [](py::object self) { return readOnlyVectorView(self.cast<const Integrator&>().displacement(), self); },
          "u (3n), a read-only view that follows the state (copy() to keep it)")
      .def_property_readonly(
          "velocity",
          [](py::object self) { return readOnlyVectorView(self.cast<const Integrator&>().velocity(), self); },
          "v (3n), a read-only view that follows the state (copy() to keep it)")
      .def_property_readonly("time", &Integrator::time)
      .def_property("timestep", &Integrator::timestep, &Integrator::setTimestep,
                    "h; setting it refactors implicit integrators at the next step")
      .def("set_timestep", &Integrator::setTimestep, py::arg("timestep"),
           "sets h; implicit integrators refactor at the next step")
      .def("mechanical_energy", &Integrator::mechanicalEnergy, py::call_guard<py::gil_scoped_release>(),
           "v^T M v / 2 + elastic energy")
      .def_property_readonly("stats", &Integrator::stats)
      .def_property_readonly("num_dofs", [](const Integrator& integrator) { return integrator.system().numDofs(); });

  singleRate<BackwardEuler>(module, "BackwardEuler", "Implicit backward Euler (linearized step, optional Newton)")
      .def_property_readonly("options", &BackwardEuler::options)
      .def_property_readonly("last_iterations", &BackwardEuler::lastIterations)
      .def_property_readonly("last_relative_residual", &BackwardEuler::lastRelativeResidual);
  singleRate<Trapezoidal>(module, "Trapezoidal", "Newmark average acceleration (trapezoidal rule)")
      .def_property_readonly("options", &Trapezoidal::options)
      .def_property_readonly("acceleration", [](Trapezoidal& integrator) { return integrator.acceleration(); })
      .def_property_readonly("last_iterations", &Trapezoidal::lastIterations)
      .def_property_readonly("last_relative_residual", &Trapezoidal::lastRelativeResidual);
  singleRate<CentralDifferences>(module, "CentralDifferences", "Explicit central differences (half-step velocity)")
      .def_property_readonly("max_frequency", &CentralDifferences::maxFrequency);
  singleRate<SymplecticEuler>(module, "SymplecticEuler", "Explicit symplectic Euler")
      .def_property_readonly("max_frequency", &SymplecticEuler::maxFrequency);

  module.def("integrator_names", &integratorNames, "names make_integrator accepts");
  module.def(
      "make_integrator",
      [](const std::string& name, const PythonDynamicSystem& system, double timestep,
         const IntegratorOptions& options) {
        DynamicSystem copy = checkedSystem(system);
        py::gil_scoped_release release;
        return makeIntegrator(name, std::move(copy), timestep, options);
      },
      py::arg("name"), py::arg("system"), py::arg("timestep"), py::arg("options") = IntegratorOptions{},
      "the integrator registered under name (integrator_names()) for this system and timestep");

  module.def("estimate_max_frequency", py::overload_cast<const TetMesh&, MassType>(&estimateMaxFrequency),
             py::arg("mesh"), py::arg("mass_type"), py::call_guard<py::gil_scoped_release>(),
             "rigorous upper bound of omega_max (rad/s) from the element matrices");
  module.def("estimate_max_frequency", py::overload_cast<const Sparse&, const Sparse&>(&estimateMaxFrequency),
             py::arg("stiffness"), py::arg("mass"), py::call_guard<py::gil_scoped_release>(),
             "estimate of omega_max from free-DOF K and M");
  module.def("stable_timestep_from_frequency", &stableTimestepFromFrequency, py::arg("max_frequency"), "2 / omega_max");
}

}  // namespace asyncfem::python
