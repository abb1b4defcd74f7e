// SPDX-License-Identifier: BSD-3-Clause
// The problem layer (Problem, VertexLoad, ProblemSettings: library problem) and scene files
// (sceneIO: load_problem, scene_mesh, run_scene).

#include <algorithm>
#include <asyncfem/problem/problem.hpp>
#include <asyncfem/runMonitor/runMonitor.hpp>
#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/sceneIO/simulation.hpp>
#include <asyncfem/sceneIO/vegaConfig.hpp>
#include <asyncfem/simulationIO/simulationFile.hpp>
#include <bindings.hpp>
#include <integrators.hpp>
#include <limits>
#include <optional>

namespace asyncfem::python {

namespace {

ForceModelType parseForceModelType(const std::string& name) {
  for (const ForceModelType type : {ForceModelType::linear, ForceModelType::corotational, ForceModelType::stvk,
                                    ForceModelType::neoHookean, ForceModelType::mooneyRivlin}) {
    if (toString(type) == name) return type;
  }
  throw py::value_error("force_model: expected one of linear, corotational, stvk, neo-hookean, mooney-rivlin, got " +
                        name);
}

void bindProblem(py::module_& module) {
  py::class_<VertexLoad>(module, "VertexLoad",
                         "The same force on each of a list of vertices while a window [start, end) is open")
      .def(py::init(
               [](const py::handle& vertices, const py::handle& perVertex, double start, double end, bool leftOpen) {
                 VertexLoad load;
                 load.vertices = indexListArgument(vertices, "vertices");
                 std::sort(load.vertices.begin(), load.vertices.end());
                 load.vertices.erase(std::unique(load.vertices.begin(), load.vertices.end()), load.vertices.end());
                 load.perVertex = toVector(perVertex, "per_vertex", 3);
                 load.start = start;
                 load.end = end;
                 load.leftOpen = leftOpen;
                 return load;
               }),
           py::arg("vertices"), py::arg("per_vertex"), py::arg("start") = 0.0,
           py::arg("end") = std::numeric_limits<double>::infinity(), py::arg("left_open") = false)
      .def_readonly("vertices", &VertexLoad::vertices)
      .def_property_readonly("per_vertex", [](const VertexLoad& l) { return Eigen::Vector3d(l.perVertex); })
      .def_readonly("start", &VertexLoad::start)
      .def_readonly("end", &VertexLoad::end)
      .def_readonly("left_open", &VertexLoad::leftOpen)
      .def("active", &VertexLoad::active, py::arg("time"), "whether the load acts at this time");

  py::class_<ProblemSettings>(module, "ProblemSettings", "Physics of a problem beyond its mesh, boundary and loads")
      .def(py::init(
               [](MassType mass, const std::string& forceModel, double alpha, double beta, const py::handle& gravity) {
                 ProblemSettings settings;
                 settings.mass = mass;
                 settings.forceModel = parseForceModelType(forceModel);
                 settings.rayleighAlpha = alpha;
                 settings.rayleighBeta = beta;
                 settings.gravity = toVector(gravity, "gravity", 3);
                 return settings;
               }),
           py::arg("mass") = MassType::consistent, py::arg("force_model") = "linear", py::arg("rayleigh_alpha") = 0.0,
           py::arg("rayleigh_beta") = 0.0, py::arg("gravity") = Eigen::Vector3d::Zero().eval())
      .def_property_readonly("force_model", [](const ProblemSettings& s) { return toString(s.forceModel); })
      .def_readonly("mass", &ProblemSettings::mass)
      .def_readonly("rayleigh_alpha", &ProblemSettings::rayleighAlpha)
      .def_readonly("rayleigh_beta", &ProblemSettings::rayleighBeta)
      .def_property_readonly("gravity", [](const ProblemSettings& s) { return Eigen::Vector3d(s.gravity); });

  py::class_<Problem, std::shared_ptr<Problem>>(
      module, "Problem",
      "Mesh, fixed vertices, physics and loads; matrices are assembled on request (assemblies counts them)")
      .def(py::init([](const TetMesh& mesh, const py::handle& fixed, const ProblemSettings& settings,
                       std::vector<VertexLoad> loads, std::shared_ptr<PenaltyContact> contact) {
             return std::make_shared<Problem>(std::make_shared<const TetMesh>(mesh),
                                              indexListArgument(fixed, "fixed_vertices"), settings, std::move(loads),
                                              std::move(contact));
           }),
           py::arg("mesh"), py::arg("fixed_vertices"), py::arg("settings") = ProblemSettings{},
           py::arg("loads") = std::vector<VertexLoad>{}, py::arg("contact") = nullptr)
      .def_property_readonly("mesh", [](const Problem& p) { return p.mesh(); })
      .def_property_readonly("fixed_vertices", &Problem::fixedVertices)
      .def_property_readonly("free_dofs", &Problem::freeDofs)
      .def_property_readonly("settings", &Problem::settings)
      .def_property_readonly("loads", &Problem::windows)
      .def_property_readonly("assemblies", &Problem::assemblies)
      .def("mass_matrix", &Problem::massMatrix, py::call_guard<py::gil_scoped_release>(),
           "M (3n x 3n), assembled on first use")
      .def("stiffness_matrix", &Problem::stiffnessMatrix, py::call_guard<py::gil_scoped_release>(),
           "K at rest (3n x 3n), assembled on first use")
      .def(
          "breakpoints", [](const Problem& p) { return p.loads()->breakpoints(); },
          "times at which a load starts, stops or is delivered")
      .def(
          "last_change", [](const Problem& p) { return p.loads()->lastChange(); },
          "the time after which no load changes any more")
      .def(
          "last_window_change", [](const Problem& p) { return p.loads()->lastWindowChange(); },
          "the last time a load window opens or closes (0 if none), contact aside: from then on only the "
          "constant load and the contact act")
      .def_property_readonly(
          "contact", [](const Problem& p) { return std::const_pointer_cast<PenaltyContact>(p.contact()); },
          "the problem's PenaltyContact, or None")
      .def(
          "constant_load", [](const Problem& p) { return Eigen::VectorXd(p.loads()->constantPart(p.numDofs())); },
          "the part of the external force that never changes (3n), e.g. gravity")
      .def(
          "external_force",
          [](const Problem& p, double time) {
            const Eigen::VectorXd zero = Eigen::VectorXd::Zero(p.numDofs());
            Eigen::VectorXd force = zero;
            p.loads()->addTo(time, zero, zero, force);
            return force;
          },
          py::arg("time"), "f_ext(t) at rest (3n)")
      .def(
          "dynamic_system",
          [](const Problem& p) {
            PythonDynamicSystem system;
            system.system = p.dynamicSystem();
            return system;
          },
          "The DynamicSystem integrators take (assembles M and K on first use)")
      .def("skipped", &Problem::skipped, "what the problem left out and why (lines for a run summary)");

  module.def(
      "load_problem",
      [](const std::filesystem::path& path) {
        py::gil_scoped_release release;
        return std::const_pointer_cast<Problem>(buildProblem(loadScene(path)));
      },
      py::arg("path"), "The problem a scene file describes (mesh, boundary, physics, loads), nothing assembled");
  module.def(
      "read_vega_config",
      [](const std::filesystem::path& path) {
        const VegaConfig config = readVegaConfig(path);
        py::dict result;
        result["scene"] = py::module_::import("json").attr("loads")(config.sceneJson.dump());
        py::list keys;
        for (const VegaConfigKey& key : config.keys) {
          py::dict entry;
          entry["key"] = key.key;
          entry["value"] = key.value;
          entry["line"] = key.line;
          entry["outcome"] = key.outcome;
          keys.append(entry);
        }
        result["keys"] = keys;
        const auto optionalPath = [](const std::optional<std::filesystem::path>& file) {
          return file ? py::cast(file->string()) : py::none();
        };
        result["rendering_mesh"] = optionalPath(config.renderingMesh);
        result["secondary_rendering_mesh"] = optionalPath(config.secondaryRenderingMesh);
        result["secondary_interpolation"] = optionalPath(config.secondaryInterpolation);
        return result;
      },
      py::arg("path"),
      "A Vega FEM simulator .config translated (docs/file-formats.md): {'scene': the equivalent scene JSON as a "
      "dict (paths relative to the config's folder), 'keys': [{key, value, line, outcome}] in file order, "
      "'rendering_mesh', 'secondary_rendering_mesh', 'secondary_interpolation': paths or None}");
}

}  // namespace

void bindScene(py::module_& module) {
  bindProblem(module);
  module.def(
      "scene_mesh",
      [](const std::filesystem::path& path) {
        py::gil_scoped_release release;
        return buildSceneMesh(loadScene(path));
      },
      py::arg("path"), "the mesh a scene file runs on (file or generator, material overrides applied)");
  py::class_<RunMonitor>(module, "RunMonitor",
                         "Watches a run for numerical failure, as offlineSimulator does: after every step a finite "
                         "state and max |u| <= blow_up_factor x the rest bounding-box diagonal, no inverted element "
                         "under a hyperelastic model without inversion handling, and after every frame of the free "
                         "phase no energy growth. A failure raises NumericalError naming the frame, step, time and "
                         "vertex (e.frame, e.step, e.time, e.vertex) with the state left at the failing step's start.")
      .def(py::init([](const Problem& problem, double blowUpFactor, bool energyCheck) {
             if (!(blowUpFactor > 0.0)) {
               throw py::value_error("blow_up_factor: expected a number > 0, got " + std::to_string(blowUpFactor));
             }
             return RunMonitor(problem, RunMonitor::Settings{blowUpFactor, energyCheck});
           }),
           py::arg("problem"), py::arg("blow_up_factor") = 1000.0, py::arg("energy_check") = true,
           py::keep_alive<1, 2>())
      .def(
          "advance_frame",
          [](RunMonitor& monitor, Integrator& integrator, long long frame, int stepsPerFrame) {
            if (stepsPerFrame < 1) {
              throw py::value_error("steps_per_frame: expected a count >= 1, got " + std::to_string(stepsPerFrame));
            }
            py::gil_scoped_release release;
            monitor.advanceFrame(integrator, frame, stepsPerFrame);
          },
          py::arg("integrator"), py::arg("frame"), py::arg("steps_per_frame"),
          "runs steps_per_frame steps of integrator with the checks; frame (0-based) is the one messages name")
      .def_property_readonly("energy_evaluations", &RunMonitor::energyEvaluations,
                             "energy checks made so far (one per frame in the free phase)");
  module.def(
      "run_scene",
      [](const std::filesystem::path& path, const std::optional<std::filesystem::path>& output,
         std::optional<int> frames, const std::optional<std::string>& integrator) {
        Scene scene = loadScene(path);
        const IntegratorRegistry registry = defaultIntegratorRegistry();
        if (integrator) switchIntegrator(scene, registry, *integrator);
        if (frames) {
          if (*frames < 1) throw py::value_error("frames: expected a count >= 1, got " + std::to_string(*frames));
          overrideFrameTiming(scene, {.frameCount = *frames});
        }
        Eigen::MatrixXd displacements;
        py::gil_scoped_release release;
        Simulation simulation = buildSimulation(scene, registry);
        std::unique_ptr<SimulationWriter> writer;
        if (output) {
          SimulationFileHeader header;
          header.numVertices = simulation.mesh->numVertices();
          header.frameInterval = simulation.timing.frameInterval;
          header.timestep = simulation.timing.timestep;
          // The records the scene's output asks for, as offlineSimulator writes them.
          header.hasVelocities = scene.output.velocities;
          describeRegionOutput(scene, simulation, header);
          describeContactForceOutput(scene, simulation, header);
          writer = std::make_unique<SimulationWriter>(*output, header);
        }
        displacements.resize(simulation.mesh->numDofs(), simulation.timing.frameCount);
        for (int frame = 0; frame < simulation.timing.frameCount; ++frame) {
          advanceFrame(simulation, frame);
          displacements.col(frame) = simulation.integrator->displacement();
          if (writer) appendSimulationFrame(*writer, simulation);
        }
        py::gil_scoped_acquire gil;
        return py::array_t<double>(py::cast(Eigen::MatrixXd(displacements.transpose())));
      },
      py::arg("path"), py::arg("output") = py::none(), py::arg("frames") = py::none(),
      py::arg("integrator") = py::none(),
      "Runs a scene file as offlineSimulator does (without checkpoints): returns the (frames, 3n) "
      "displacements after each frame and writes them to output (.afsim) if given, with the velocities, contact "
      "forces and region ratios the scene's output asks for. integrator replaces "
      "the scene's (its options that the new one does not read are dropped).");
}

}  // namespace asyncfem::python
