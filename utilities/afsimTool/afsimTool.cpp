// SPDX-License-Identifier: BSD-3-Clause
// afsimTool: gets results out of a simulation output file (.afsim).
//
//   afsimTool info SIM.afsim
//   afsimTool csv SIM.afsim --vertices 12,40 [--frames 0:100] [--mesh MESH | --scene SCENE.json] [-o FILE.csv]
//   afsimTool vtu SIM.afsim (--mesh MESH | --scene SCENE.json) [--frames 10,20] [-o DIR] [--encoding binary|ascii]
//   afsimTool intersections SIM.afsim [--scene SCENE.json] [--frames 0:100]
//
// info prints the header, the frame times, the fast vertices of the first and last frame
// when the records carry region ratios, whether every record's checksum matches (else
// the first bad frame, exit status 1) and the run's checkpoint when one lies next to the
// file. csv writes one row per frame: index, time and the chosen vertices' displacement
// (and rest + displacement positions with a mesh). vtu writes DIR/frame_NNNNN.vtu per
// chosen frame and DIR/frames.pvd. intersections checks every chosen frame's surfaces exactly
// (intersections.hpp): intersecting triangle pairs between and within the bodies and against
// mesh obstacles, and the deepest penetration of the analytic obstacles. Errors print "afsimTool: <message>" on stderr
// and exit with status 1. Described in docs/simulation-output.md, section "Getting results out".
#include <CLI/CLI.hpp>
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/sceneIO/simulation.hpp>
#include <asyncfem/simulationIO/checkpoint.hpp>
#include <asyncfem/simulationIO/frameSelection.hpp>
#include <asyncfem/simulationIO/simulationFile.hpp>
#include <asyncfem/volumetricMesh/readers.hpp>
#include <asyncfem/volumetricMesh/writers.hpp>
#include <charconv>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "intersections.hpp"

namespace {

namespace fs = std::filesystem;
using namespace asyncfem;

struct CommandLine {
  std::string simulation;
  std::string vertices;
  std::string frames;
  std::optional<std::string> mesh;
  std::optional<std::string> scene;
  std::string output;
  std::string encoding = "binary";
};

/// The shortest text that reads back to the same double.
std::string exact(double value) {
  char text[32];
  const auto result = std::to_chars(text, text + sizeof(text), value);
  return {text, result.ptr};
}

std::string hex(std::uint32_t value) {
  char text[16];
  std::snprintf(text, sizeof(text), "0x%08x", value);
  return text;
}

/// Opens the file; a missing or unreadable one is named with the reason.
std::unique_ptr<SimulationReader> openSimulation(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw Error("cannot open '" + path + "': no such file");
  if (fs::is_directory(path, ec)) throw Error("cannot open '" + path + "': it is a folder, not an .afsim file");
  return std::make_unique<SimulationReader>(path);
}

/// "12,40" -> {12, 40}; every id must be a vertex of the file.
std::vector<int> parseVertices(const std::string& text, const SimulationReader& reader) {
  std::vector<int> vertices;
  std::string item;
  for (std::size_t i = 0; i <= text.size(); ++i) {
    if (i < text.size() && text[i] != ',') {
      item += text[i];
      continue;
    }
    long long id = -1;
    const auto [end, error] = std::from_chars(item.data(), item.data() + item.size(), id);
    if (item.empty() || error != std::errc() || end != item.data() + item.size() || id < 0) {
      throw Error("--vertices " + text + ": \"" + item + "\" is not a vertex id (expected 0-based ids such as 12,40)");
    }
    if (id >= reader.numVertices()) {
      throw Error("--vertices: vertex " + std::to_string(id) + " is out of range: " + reader.path().string() + " has " +
                  std::to_string(reader.numVertices()) + " vertices (ids 0 to " +
                  std::to_string(reader.numVertices() - 1) + ")");
    }
    vertices.push_back(static_cast<int>(id));
    item.clear();
  }
  return vertices;
}

/// The mesh from --mesh or --scene (none if neither), checked against the file's vertex count.
std::optional<TetMesh> loadMesh(const CommandLine& options, const SimulationReader& reader) {
  if (options.mesh && options.scene) throw Error("give the mesh with --mesh FILE or --scene SCENE.json, not both");
  std::optional<TetMesh> mesh;
  std::string name;
  std::vector<std::string> warnings;
  if (options.mesh) {
    mesh = readMeshCollectingWarnings(*options.mesh, warnings);
    name = *options.mesh;
  } else if (options.scene) {
    mesh = buildSceneMesh(loadScene(*options.scene), &warnings);
    name = *options.scene;
  } else if (!reader.header().scenePath.empty()) {
    // The scene the run recorded (checked against its fingerprint).
    mesh = recordedSceneProblem(reader.header(), reader.path().string(), &warnings)->mesh();
    name = reader.header().scenePath;
  } else {
    return mesh;
  }
  for (const std::string& warning : warnings) std::cerr << "afsimTool: warning: " << warning << '\n';
  if (mesh->numVertices() != reader.numVertices()) {
    throw Error(reader.path().string() + " has " + std::to_string(reader.numVertices()) + " vertices but the mesh (" +
                name + ") has " + std::to_string(mesh->numVertices()) + ": the simulation did not run on this mesh");
  }
  return mesh;
}

/// The header lines of info: file, format, scene, sizes, frame rate, record size.
void printHeader(const std::string& simulation, const SimulationReader& reader) {
  const SimulationFileHeader& header = reader.header();
  std::cout << "file        " << simulation << " (" << fs::file_size(simulation) << " bytes)\n"
            << "format      AsyncFEM simulation file, version " << (header.scenePath.empty() ? 1 : 2) << '\n';
  if (!header.scenePath.empty()) {
    char fingerprint[16];
    std::snprintf(fingerprint, sizeof(fingerprint), "%08x", header.sceneFingerprint);
    std::cout << "scene       " << header.scenePath << " (mesh and fixed vertices fingerprint " << fingerprint << ")\n";
  }
  std::cout << "vertices    " << header.numVertices << '\n' << "frames      " << reader.numFrames() << " complete";
  if (reader.hasTruncatedFrame()) {
    std::cout << " (+ " << reader.truncatedTrailingBytes() << " bytes of an interrupted frame, ignored)";
  }
  std::cout << "\nframe rate  " << exact(header.frameInterval > 0 ? 1.0 / header.frameInterval : 0.0)
            << " per time unit (interval " << exact(header.frameInterval) << ")\n"
            << "timestep    " << (header.timestep > 0 ? exact(header.timestep) : std::string("unknown")) << '\n'
            << "velocities  " << (header.hasVelocities ? "yes" : "no") << '\n'
            << "record      " << header.recordBytes() << " bytes\n";
}

/// The checkpoint lines of info; a version-1 file records no scene (printHeader prints a
/// recorded one), and then the checkpoint's run fingerprint identifies the run.
void printCheckpoint(const std::string& simulation, const SimulationFileHeader& header) {
  const fs::path checkpointFile = checkpointPathFor(simulation);
  if (header.scenePath.empty()) std::cout << "scene       not recorded in the .afsim file\n";
  if (!fs::exists(checkpointFile)) {
    std::cout << "checkpoint  none (" << checkpointFile.string() << " does not exist)\n";
    return;
  }
  try {
    const SimulationCheckpoint checkpoint = readCheckpoint(checkpointFile);
    std::cout << "checkpoint  " << checkpointFile.string() << ": after frame " << checkpoint.frames
              << ", t = " << exact(checkpoint.time) << ", integrator " << checkpoint.integrator << "; run fingerprint "
              << hex(checkpoint.fingerprint) << " (scene, mesh, timestep)\n";
  } catch (const Error& error) {
    std::cout << "checkpoint  " << checkpointFile.string() << ": unreadable: " << error.what() << '\n';
  }
}

/// The regions line of info: whether the records carry region ratios and, when they do,
/// how many vertices were fast (ratio above 1) in the first and the last good frame.
void printRegions(SimulationReader& reader, const RecordScan& scan) {
  std::cout << "regions     ";
  if (!reader.header().hasRegionRatios) {
    std::cout << "no (the records carry no region ratios)\n";
    return;
  }
  std::cout << "yes, each vertex's step ratio per frame";
  const auto fastIn = [&](std::int64_t k) {
    const std::vector<std::uint16_t> ratios = reader.readFrame(k).regionRatios;
    return std::count_if(ratios.begin(), ratios.end(), [](std::uint16_t ratio) { return ratio > 1; });
  };
  if (scan.goodFrames > 0) {
    const std::int64_t last = scan.goodFrames - 1;
    std::cout << ": " << fastIn(0) << " fast vertices in the first frame, " << fastIn(last) << " in the last (frame "
              << last << ")";
  }
  std::cout << '\n';
}

int info(const CommandLine& options) {
  const auto reader = openSimulation(options.simulation);
  printHeader(options.simulation, *reader);
  // Every record, so that the times come from the file and a bad checksum is found.
  const RecordScan scan = reader->scanRecords();
  if (reader->numFrames() > 0) {
    std::cout << "times       " << exact(scan.firstTime) << " to " << exact(scan.lastTime) << '\n';
  }
  printRegions(*reader, scan);
  std::cout << "checksums   "
            << (scan.badFrame ? "BAD: " + scan.badMessage : "ok (" + std::to_string(reader->numFrames()) + " frames)")
            << '\n';
  printCheckpoint(options.simulation, reader->header());
  if (scan.badFrame) {
    std::cerr << "afsimTool: " << scan.badMessage << '\n';
    return 1;
  }
  return 0;
}

/// The CSV header row: frame, time and per vertex its displacement (and with a mesh its
/// position) components.
void writeCsvHeader(std::ostream& out, const std::vector<int>& vertices, bool withPositions) {
  out << "frame,time";
  for (const int v : vertices) {
    for (const char* axis : {"x", "y", "z"}) out << ",u" << v << '_' << axis;
    if (withPositions) {
      for (const char* axis : {"x", "y", "z"}) out << ",p" << v << '_' << axis;
    }
  }
  out << '\n';
}

int csv(const CommandLine& options) {
  const auto reader = openSimulation(options.simulation);
  const std::vector<int> vertices = parseVertices(options.vertices, *reader);
  const std::vector<std::int64_t> frames =
      frames::selectFrames(frames::parseFrameSelection(options.frames), reader->numFrames(), options.simulation);
  const std::optional<TetMesh> mesh = loadMesh(options, *reader);

  std::ofstream file;
  if (!options.output.empty()) {
    const fs::path output(options.output);
    if (output.has_parent_path()) fs::create_directories(output.parent_path());
    file.open(output, std::ios::trunc);
    if (!file) throw Error("cannot write '" + options.output + "'");
  }
  std::ostream& out = options.output.empty() ? std::cout : file;
  writeCsvHeader(out, vertices, mesh.has_value());
  SimulationFrame frame;
  for (const std::int64_t k : frames) {
    reader->readFrame(k, frame);
    out << k << ',' << exact(frame.time);
    for (const int v : vertices) {
      const Eigen::Vector3d u = frame.displacement.segment<3>(3 * v);
      for (int axis = 0; axis < 3; ++axis) out << ',' << exact(u[axis]);
      if (mesh) {
        const Eigen::Vector3d position = mesh->restPosition(v) + u;
        for (int axis = 0; axis < 3; ++axis) out << ',' << exact(position[axis]);
      }
    }
    out << '\n';
  }
  out.flush();
  if (!out) throw Error("cannot write '" + (options.output.empty() ? std::string("stdout") : options.output) + "'");
  return 0;
}

int vtu(const CommandLine& options) {
  const auto reader = openSimulation(options.simulation);
  if (!options.mesh && !options.scene) throw Error("vtu needs the mesh: give --mesh FILE or --scene SCENE.json");
  const std::vector<std::int64_t> frames =
      frames::selectFrames(frames::parseFrameSelection(options.frames), reader->numFrames(), options.simulation);
  const std::optional<TetMesh> mesh = loadMesh(options, *reader);
  VtuSeriesWriter series(options.output.empty() ? fs::path("vtu") : fs::path(options.output),
                         options.encoding == "ascii" ? VtuEncoding::ascii : VtuEncoding::binary);
  SimulationFrame frame;
  for (const std::int64_t k : frames) {
    reader->readFrame(k, frame);
    series.writeFrame(k, frame.time, *mesh, frame.displacement);
  }
  std::cout << "wrote " << frames.size() << " .vtu files and " << series.collectionPath().string() << '\n';
  return 0;
}

int run(int argc, char** argv) {
  CLI::App app{"Gets results out of an .afsim simulation file (docs/simulation-output.md)."};
  app.require_subcommand(1);
  CommandLine options;

  CLI::App* infoCommand = app.add_subcommand("info", "Header, frame times, checksums, the run's checkpoint");
  infoCommand->add_option("simulation", options.simulation, "The .afsim file")->required();

  CLI::App* csvCommand = app.add_subcommand("csv", "Chosen vertices' displacements (and positions) per frame as CSV");
  csvCommand->add_option("simulation", options.simulation, "The .afsim file")->required();
  csvCommand->add_option("--vertices", options.vertices, "0-based vertex ids, comma separated (12,40)")->required();
  csvCommand->add_option("--frames", options.frames, "Frames, start:stop:step or a comma list (default all)");
  csvCommand->add_option("--mesh", options.mesh, "The tet mesh: also write positions (rest + displacement)");
  csvCommand->add_option("--scene", options.scene, "Instead of --mesh: the scene that produced the file");
  csvCommand->add_option("-o,--output", options.output, "CSV file to write (default: stdout)");

  CLI::App* vtuCommand = app.add_subcommand("vtu", "Chosen frames as .vtu files plus a .pvd collection");
  vtuCommand->add_option("simulation", options.simulation, "The .afsim file")->required();
  vtuCommand->add_option("--mesh", options.mesh, "The tet mesh the simulation ran on (.veg, .node/.ele, .msh)");
  vtuCommand->add_option("--scene", options.scene, "Instead of --mesh: the scene that produced the file");
  vtuCommand->add_option("--frames", options.frames, "Frames, start:stop:step or a comma list (default all)");
  vtuCommand->add_option("-o,--output", options.output, "Folder for frame_NNNNN.vtu and frames.pvd (default vtu)");
  vtuCommand->add_option("--encoding", options.encoding, "binary (raw appended, default) or ascii")
      ->check(CLI::IsMember({"binary", "ascii"}));

  CLI::App* intersectionsCommand = app.add_subcommand(
      "intersections", "Per frame: intersecting surface triangle pairs and the deepest obstacle penetration (CSV)");
  intersectionsCommand->add_option("simulation", options.simulation, "The .afsim file")->required();
  intersectionsCommand->add_option("--scene", options.scene,
                                   "The scene that produced the file (default: the recorded one)");
  intersectionsCommand->add_option("--frames", options.frames, "Frames, start:stop:step or a comma list (default all)");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    return app.exit(error);
  }
  if (infoCommand->parsed()) return info(options);
  if (csvCommand->parsed()) return csv(options);
  if (intersectionsCommand->parsed())
    return afsimtool::intersections(options.simulation, options.scene, options.frames);
  return vtu(options);
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const asyncfem::Error& e) {
    std::cerr << "afsimTool: " << e.what() << '\n';
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "afsimTool: unexpected error: " << e.what() << '\n';
    return 1;
  }
}
