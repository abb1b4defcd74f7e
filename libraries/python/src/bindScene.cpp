// SPDX-License-Identifier: BSD-3-Clause
// Scene files through today's sceneIO API (loadScene, buildSimulation, advanceFrame), kept
// in this one file on purpose: the scene layer is being redesigned, and this is the only
// place the module touches it.

#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/sceneIO/simulation.hpp>
#include <asyncfem/simulationIO/simulationFile.hpp>
#include <bindings.hpp>
#include <optional>

namespace asyncfem::python {

void bindScene(py::module_& module) {
  module.def(
      "scene_mesh",
      [](const std::filesystem::path& path) {
        py::gil_scoped_release release;
        return buildSceneMesh(loadScene(path));
      },
      py::arg("path"), "the mesh a scene file runs on (file or generator, material overrides applied)");
  module.def(
      "run_scene",
      [](const std::filesystem::path& path, const std::optional<std::filesystem::path>& output,
         std::optional<int> frames, const std::optional<std::string>& integrator) {
        Scene scene = loadScene(path);
        const IntegratorRegistry registry = defaultIntegratorRegistry();
        if (integrator) switchIntegrator(scene, registry, *integrator);
        if (frames) {
          if (*frames < 1) throw py::value_error("frames: expected a count >= 1, got " + std::to_string(*frames));
          scene.frames.count = *frames;
        }
        Eigen::MatrixXd displacements;
        py::gil_scoped_release release;
        Simulation simulation = buildSimulation(scene, registry);
        std::unique_ptr<SimulationWriter> writer;
        if (output) {
          SimulationFileHeader header;
          header.numVertices = simulation.mesh->numVertices();
          header.frameInterval = simulation.frameInterval;
          header.timestep = simulation.timestep;
          writer = std::make_unique<SimulationWriter>(*output, header);
        }
        displacements.resize(simulation.mesh->numDofs(), simulation.numFrames);
        for (int frame = 0; frame < simulation.numFrames; ++frame) {
          advanceFrame(simulation, frame);
          displacements.col(frame) = simulation.integrator->displacement();
          if (writer) writer->appendFrame(simulation.integrator->time(), simulation.integrator->displacement());
        }
        py::gil_scoped_acquire gil;
        return py::array_t<double>(py::cast(Eigen::MatrixXd(displacements.transpose())));
      },
      py::arg("path"), py::arg("output") = py::none(), py::arg("frames") = py::none(),
      py::arg("integrator") = py::none(),
      "Runs a scene file as offlineSimulator does (without checkpoints): returns the (frames, 3n) "
      "displacements after each frame and writes them to output (.afsim) if given. integrator replaces "
      "the scene's (its options that the new one does not read are dropped).");
}

}  // namespace asyncfem::python
