// SPDX-License-Identifier: BSD-3-Clause
// libraries/simulationIO: the .afsim frame file, written and read.

#include <asyncfem/simulationIO/simulationFile.hpp>
#include <bindings.hpp>

namespace asyncfem::python {

void bindOutput(py::module_& module) {
  py::class_<SimulationFileHeader>(module, "SimulationFileHeader",
                                   "Header of an .afsim file: vertices, frame interval, timestep, velocities")
      .def(py::init([](std::int64_t numVertices, double frameInterval, double timestep, bool hasVelocities) {
             SimulationFileHeader header;
             header.numVertices = numVertices;
             header.frameInterval = frameInterval;
             header.timestep = timestep;
             header.hasVelocities = hasVelocities;
             return header;
           }),
           py::arg("num_vertices"), py::arg("frame_interval"), py::arg("timestep") = 0.0,
           py::arg("has_velocities") = false)
      .def_readwrite("num_vertices", &SimulationFileHeader::numVertices)
      .def_readwrite("frame_interval", &SimulationFileHeader::frameInterval)
      .def_readwrite("timestep", &SimulationFileHeader::timestep)
      .def_readwrite("has_velocities", &SimulationFileHeader::hasVelocities)
      .def_property_readonly(
          "has_region_ratios", [](const SimulationFileHeader& header) { return header.hasRegionRatios; },
          "True when each record also carries every vertex's step ratio (header flag bit 1; offlineSimulator's "
          "output.regions)")
      .def_property_readonly(
          "has_contact_forces", [](const SimulationFileHeader& header) { return header.hasContactForces; },
          "True when each record also carries every vertex's contact force (header flag bit 2; offlineSimulator's "
          "output.contactForces)")
      .def_property_readonly("record_bytes", &SimulationFileHeader::recordBytes);

  py::class_<SimulationFrame>(module, "SimulationFrame",
                              "One frame read from an .afsim file: index, time, displacement (and velocity)")
      .def_readonly("index", &SimulationFrame::index)
      .def_readonly("time", &SimulationFrame::time)
      .def_readonly("displacement", &SimulationFrame::displacement)
      .def_readonly("velocity", &SimulationFrame::velocity)
      .def_readonly("contact_force", &SimulationFrame::contactForce,
                    "every vertex's contact force (3n, N) at the frame's state; empty when the file records none "
                    "(offlineSimulator's output.contactForces)")
      .def_property_readonly(
          "region_ratios",
          [](const SimulationFrame& frame) {
            return py::array_t<std::uint16_t>(static_cast<py::ssize_t>(frame.regionRatios.size()),
                                              frame.regionRatios.data());
          },
          "each vertex's step ratio to the large step (uint16: 1 in L, m_i in fast region S_i); empty when the "
          "file records none");

  py::class_<SimulationWriter>(module, "SimulationWriter",
                               "Append-only .afsim file: one checksummed record per frame, flushed at once")
      .def(py::init([](const std::filesystem::path& path, const SimulationFileHeader& header, bool sync) {
             return std::make_unique<SimulationWriter>(path, header, SimulationWriter::Options{sync});
           }),
           py::arg("path"), py::arg("header"), py::arg("sync_each_frame") = false)
      .def(
          "append_frame",
          [](SimulationWriter& writer, double time, const py::handle& displacement, const py::object& velocity) {
            const Eigen::Index n = 3 * writer.header().numVertices;
            const auto u = vectorArgument(displacement, "displacement", n);
            if (writer.header().hasVelocities != !velocity.is_none()) {
              throw py::value_error(writer.header().hasVelocities ? "velocity: the header says frames carry velocities"
                                                                  : "velocity: the header says frames carry none");
            }
            if (velocity.is_none()) {
              writer.appendFrame(time, asVector(u));  // no copy: the library takes Eigen::Ref
            } else {
              const auto v = vectorArgument(velocity, "velocity", n);
              writer.appendFrame(time, asVector(u), asVector(v));
            }
          },
          py::arg("time"), py::arg("displacement"), py::arg("velocity") = py::none(),
          "appends one frame (time, displacement 3n, optional velocity) and flushes it")
      .def_property_readonly("num_frames", &SimulationWriter::numFrames)
      .def_property_readonly("header", &SimulationWriter::header)
      .def_property_readonly("path", &SimulationWriter::path)
      .def("close", &SimulationWriter::close, "closes the file (frames already appended stay readable)")
      .def("__enter__", [](py::object self) { return self; })
      .def("__exit__", [](SimulationWriter& writer, const py::args&) { writer.close(); });

  py::class_<SimulationReader>(module, "SimulationReader", "Reads an .afsim file, checking every record")
      .def(py::init<const std::filesystem::path&>(), py::arg("path"))
      .def_property_readonly("header", &SimulationReader::header)
      .def_property_readonly("path", &SimulationReader::path)
      .def_property_readonly("num_vertices", &SimulationReader::numVertices)
      .def_property_readonly("num_frames", &SimulationReader::numFrames)
      .def_property_readonly("truncated_trailing_bytes", &SimulationReader::truncatedTrailingBytes)
      .def("refresh", &SimulationReader::refresh, "re-reads the file size, for a file another process is still writing")
      .def(
          "read_frame",
          [](SimulationReader& reader, std::int64_t k) {
            checkIndex(k, reader.numFrames(), "frame");
            py::gil_scoped_release release;
            return reader.readFrame(k);
          },
          py::arg("frame"), "frame k, its checksum and index verified (ParseError naming the frame otherwise)")
      .def("verify_all", &SimulationReader::verifyAll, py::call_guard<py::gil_scoped_release>(),
           "checks the checksum of every complete frame (ParseError naming the first bad one)")
      .def("__len__", &SimulationReader::numFrames)
      .def(
          "displacements",
          [](SimulationReader& reader) {
            const auto frames = reader.numFrames();
            const auto n = static_cast<py::ssize_t>(3 * reader.numVertices());
            py::array_t<double> result({static_cast<py::ssize_t>(frames), n});
            double* out = result.mutable_data();
            {
              py::gil_scoped_release release;
              SimulationFrame frame;
              for (std::int64_t k = 0; k < frames; ++k) {
                reader.readFrame(k, frame);
                std::copy(frame.displacement.data(), frame.displacement.data() + n, out + (k * n));
              }
            }
            return result;
          },
          "(frames, 3n) array of every frame's displacement")
      .def(
          "region_ratios",
          [](SimulationReader& reader) {
            if (!reader.header().hasRegionRatios) {
              throw py::value_error(reader.path().string() +
                                    " does not record region ratios (header flag bit 1): run the scene with "
                                    "\"output\": {\"regions\": true}");
            }
            const auto frames = reader.numFrames();
            const auto n = static_cast<py::ssize_t>(reader.numVertices());
            py::array_t<std::uint16_t> result({static_cast<py::ssize_t>(frames), n});
            std::uint16_t* out = result.mutable_data();
            {
              py::gil_scoped_release release;
              SimulationFrame frame;
              for (std::int64_t k = 0; k < frames; ++k) {
                reader.readFrame(k, frame);
                std::copy(frame.regionRatios.begin(), frame.regionRatios.end(), out + (k * n));
              }
            }
            return result;
          },
          "(frames, n) uint16 array of every frame's step ratio per vertex (1 in the large-step region, m_i in fast "
          "region S_i), for runs that record their regions; ValueError for a file without them");
}

}  // namespace asyncfem::python
