// SPDX-License-Identifier: BSD-3-Clause
#include "harnesses.hpp"

#include <unistd.h>

#include <asyncfem/core/error.hpp>
#include <asyncfem/sceneIO/scene.hpp>
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

void readMeshQuietly(const fs::path& path,
                     TetMesh (*reader)(const fs::path&, const MeshReadOptions&, MeshReadReport*)) {
  try {
    MeshReadReport report;
    const TetMesh mesh = reader(path, MeshReadOptions{}, &report);
    // A mesh that reads is valid (the TetMesh constructor checks it); touch it so that a
    // broken one would show up under the sanitizers.
    if (mesh.numElements() <= 0 || !mesh.restPositions().allFinite()) std::abort();
  } catch (const Error&) {
    // Rejected with a documented error: expected for most inputs.
  }
}

}  // namespace

int fuzzVeg(const std::uint8_t* data, std::size_t size) {
  readMeshQuietly(writeInput("input.veg", data, size), readVeg);
  return 0;
}

int fuzzTetGen(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  constexpr std::string_view separator = "@@ele\n";
  std::size_t split = text.find(separator);
  std::size_t eleStart = split == std::string_view::npos ? size : split + separator.size();
  if (split == std::string_view::npos) split = size;
  writeInput("input.node", data, split);
  writeInput("input.ele", data + eleStart, size - eleStart);
  readMeshQuietly(scratchFolder() / "input.node", readTetGen);
  return 0;
}

int fuzzGmsh(const std::uint8_t* data, std::size_t size) {
  readMeshQuietly(writeInput("input.msh", data, size), readGmsh);
  return 0;
}

int fuzzSimulationFile(const std::uint8_t* data, std::size_t size) {
  const fs::path path = writeInput("input.afsim", data, size);
  try {
    SimulationReader reader(path);
    SimulationFrame frame;
    for (std::int64_t k = 0; k < reader.numFrames(); ++k) {
      try {
        reader.readFrame(k, frame);
      } catch (const ParseError&) {
        // A corrupted record is reported; the reader stays usable for the others.
      }
    }
  } catch (const Error&) {
  }
  try {
    const SimulationCheckpoint checkpoint = parseCheckpoint(data, size, "input.checkpoint");
    if (checkpoint.displacement.size() != checkpoint.velocity.size()) std::abort();
  } catch (const Error&) {
  }
  return 0;
}

int fuzzScene(const std::uint8_t* data, std::size_t size) {
  nlohmann::json json;
  try {
    json = nlohmann::json::parse(data, data + size, nullptr, true, /*ignore_comments=*/true);
  } catch (const nlohmann::json::exception&) {
    return 0;  // not JSON: loadScene reports it as a ParseError before parseScene runs
  }
  try {
    const Scene scene = parseScene(json, scratchFolder(), "fuzz.json");
    static_cast<void>(scene);
  } catch (const Error&) {
  }
  return 0;
}

std::vector<Harness> allHarnesses() {
  return {{"veg", fuzzVeg},
          {"tetgen", fuzzTetGen},
          {"gmsh", fuzzGmsh},
          {"simulationFile", fuzzSimulationFile},
          {"scene", fuzzScene}};
}

}  // namespace asyncfem::fuzz
