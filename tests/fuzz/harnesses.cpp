// SPDX-License-Identifier: BSD-3-Clause
#include "harnesses.hpp"

#include <unistd.h>

#include <asyncfem/core/error.hpp>
#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/sceneIO/simulation.hpp>
#include <asyncfem/simulationIO/checkpoint.hpp>
#include <asyncfem/simulationIO/simulationFile.hpp>
#include <asyncfem/volumetricMesh/readers.hpp>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string_view>
#include <system_error>

namespace asyncfem::fuzz {

namespace {

namespace fs = std::filesystem;

// The readers take paths, so each input goes through a file in a folder of this process,
// removed when the process exits normally (libFuzzer's -max_total_time ends with exit()).
class ScratchFolder {
 public:
  ScratchFolder() : path_(fs::temp_directory_path() / ("asyncfem-fuzz-" + std::to_string(::getpid()))) {
    fs::create_directories(path_);
  }
  ~ScratchFolder() {
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  ScratchFolder(const ScratchFolder&) = delete;
  ScratchFolder& operator=(const ScratchFolder&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

const fs::path& scratchFolder() {
  static const ScratchFolder folder;
  return folder.path();
}

fs::path writeInput(const std::string& name, const std::uint8_t* data, std::size_t size) {
  const fs::path path = scratchFolder() / name;
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr) throw std::runtime_error("fuzz harness: cannot write " + path.string());
  if (size > 0 && std::fwrite(data, 1, size, file) != size) {
    std::fclose(file);
    throw std::runtime_error("fuzz harness: cannot write " + path.string());
  }
  std::fclose(file);
  return path;
}

// The outcome of a rejected input: the error's class and its message, with the scratch
// folder (which holds the process id) replaced by "<scratch>".
std::string rejected(const Error& error) {
  const char* kind = "Error";
  if (dynamic_cast<const TimestepError*>(&error) != nullptr) {
    kind = "TimestepError";
  } else if (dynamic_cast<const ValidationError*>(&error) != nullptr) {
    kind = "ValidationError";
  } else if (dynamic_cast<const ParseError*>(&error) != nullptr) {
    kind = "ParseError";
  } else if (dynamic_cast<const NumericalError*>(&error) != nullptr) {
    kind = "NumericalError";
  }
  std::string message = error.what();
  const std::string folder = scratchFolder().string();
  for (std::size_t at = message.find(folder); at != std::string::npos; at = message.find(folder, at)) {
    message.replace(at, folder.size(), "<scratch>");
  }
  return "rejected: " + std::string(kind) + ": " + message;
}

std::string readMesh(const fs::path& path,
                     TetMesh (*reader)(const fs::path&, const MeshReadOptions&, MeshReadReport*)) {
  try {
    MeshReadReport report;
    const TetMesh mesh = reader(path, MeshReadOptions{}, &report);
    // A mesh that reads is valid (the TetMesh constructor checks it); touch it so that a
    // broken one would show up under the sanitizers.
    if (mesh.numElements() <= 0 || !mesh.restPositions().allFinite()) std::abort();
    return "accepted: " + std::to_string(mesh.numVertices()) + " vertices, " + std::to_string(mesh.numElements()) +
           " elements";
  } catch (const Error& error) {
    // Rejected with a documented error: expected for most inputs.
    return rejected(error);
  }
}

}  // namespace

std::string vegOutcome(const std::uint8_t* data, std::size_t size) {
  return readMesh(writeInput("input.veg", data, size), readVeg);
}

std::string tetGenOutcome(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  constexpr std::string_view separator = "@@ele\n";
  std::size_t split = text.find(separator);
  std::size_t eleStart = split == std::string_view::npos ? size : split + separator.size();
  if (split == std::string_view::npos) split = size;
  writeInput("input.node", data, split);
  writeInput("input.ele", data + eleStart, size - eleStart);
  return readMesh(scratchFolder() / "input.node", readTetGen);
}

std::string gmshOutcome(const std::uint8_t* data, std::size_t size) {
  return readMesh(writeInput("input.msh", data, size), readGmsh);
}

std::string simulationFileOutcome(const std::uint8_t* data, std::size_t size) {
  const fs::path path = writeInput("input.afsim", data, size);
  std::string outcome = "reader: ";
  try {
    SimulationReader reader(path);
    SimulationFrame frame;
    std::int64_t good = 0;
    std::string bad;
    for (std::int64_t k = 0; k < reader.numFrames(); ++k) {
      try {
        reader.readFrame(k, frame);
        ++good;
      } catch (const ParseError& error) {
        // A corrupted record is reported; the reader stays usable for the others.
        bad += "; frame " + std::to_string(k) + ": " + rejected(error);
      }
    }
    outcome += "accepted: " + std::to_string(reader.numVertices()) + " vertices, " + std::to_string(good) + " of " +
               std::to_string(reader.numFrames()) + " frames read" + bad;
  } catch (const Error& error) {
    outcome += rejected(error);
  }
  outcome += "; checkpoint: ";
  try {
    const SimulationCheckpoint checkpoint = parseCheckpoint(data, size, "input.checkpoint");
    if (checkpoint.displacement.size() != checkpoint.velocity.size()) std::abort();
    outcome += "accepted: " + checkpoint.integrator + ", " + std::to_string(checkpoint.frames) + " frames, " +
               std::to_string(checkpoint.displacement.size()) + " state entries";
  } catch (const Error& error) {
    outcome += rejected(error);
  }
  return outcome;
}

namespace {

// A box generator of at most 64 cells: built in milliseconds, so fuzzing stays fast and no
// input can ask the harness for a huge mesh (beams and mesh files are parsed only).
bool smallGeneratedMesh(const Scene& scene) {
  constexpr long long kMaxCells = 64;
  if (scene.mesh.source != Scene::MeshSource::box) return false;
  const Eigen::Vector3i& cells = scene.mesh.box.cells;
  return cells.minCoeff() > 0 && static_cast<long long>(cells.x()) * cells.y() * cells.z() <= kMaxCells;
}

}  // namespace

std::string sceneOutcome(const std::uint8_t* data, std::size_t size) {
  nlohmann::json json;
  try {
    json = nlohmann::json::parse(data, data + size, nullptr, true, /*ignore_comments=*/true);
  } catch (const nlohmann::json::exception& error) {
    // Not JSON: loadScene reports it as a ParseError before parseScene runs.
    return std::string("not JSON: ") + error.what();
  }
  try {
    const Scene scene = parseScene(json, scratchFolder(), "fuzz.json");
    if (!smallGeneratedMesh(scene)) return "accepted: integrator " + scene.integrator.name + " (parsed only)";
    // Small generated meshes are built too, so that what parseScene passes on unread
    // reaches its readers: the integrator's options (async regions, adaptive policies,
    // reuseFactor, ...), the force model's options and the fixed and loaded vertices.
    const Simulation simulation = buildSimulation(scene);
    return "accepted: integrator " + simulation.integrator->name() + ", built with " +
           std::to_string(simulation.mesh->numVertices()) + " vertices";
  } catch (const Error& error) {
    return rejected(error);
  }
}

int fuzzVeg(const std::uint8_t* data, std::size_t size) {
  static_cast<void>(vegOutcome(data, size));
  return 0;
}

int fuzzTetGen(const std::uint8_t* data, std::size_t size) {
  static_cast<void>(tetGenOutcome(data, size));
  return 0;
}

int fuzzGmsh(const std::uint8_t* data, std::size_t size) {
  static_cast<void>(gmshOutcome(data, size));
  return 0;
}

int fuzzSimulationFile(const std::uint8_t* data, std::size_t size) {
  static_cast<void>(simulationFileOutcome(data, size));
  return 0;
}

int fuzzScene(const std::uint8_t* data, std::size_t size) {
  static_cast<void>(sceneOutcome(data, size));
  return 0;
}

std::vector<Harness> allHarnesses() {
  return {{"veg", fuzzVeg, vegOutcome},
          {"tetgen", fuzzTetGen, tetGenOutcome},
          {"gmsh", fuzzGmsh, gmshOutcome},
          {"simulationFile", fuzzSimulationFile, simulationFileOutcome},
          {"scene", fuzzScene, sceneOutcome}};
}

}  // namespace asyncfem::fuzz
