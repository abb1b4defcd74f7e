// SPDX-License-Identifier: BSD-3-Clause
#include "harnesses.hpp"

#include <unistd.h>

#include <asyncfem/core/error.hpp>
#include <asyncfem/simulationIO/checkpoint.hpp>
#include <asyncfem/simulationIO/simulationFile.hpp>
#include <asyncfem/volumetricMesh/readers.hpp>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string_view>
#include <system_error>

#include "harnessSupport.hpp"

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

}  // namespace

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

// A rejected input's summary: the error's class and its message, with the scratch folder
// (which holds the process id) replaced by "<scratch>".
std::string describe(const Error& error) {
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
  return std::string(kind) + ": " + message;
}

namespace {

Outcome readMesh(const std::function<fs::path()>& writeFiles,
                 TetMesh (*reader)(const fs::path&, const MeshReadOptions&, MeshReadReport*)) {
  return classify([&] {
    MeshReadReport report;
    const TetMesh mesh = reader(writeFiles(), MeshReadOptions{}, &report);
    // A mesh that reads is valid (the TetMesh constructor checks it); touch it so that a
    // broken one would show up under the sanitizers.
    if (mesh.numElements() <= 0 || !mesh.restPositions().allFinite()) std::abort();
    return std::to_string(mesh.numVertices()) + " vertices, " + std::to_string(mesh.numElements()) + " elements";
  });
}

}  // namespace

// libFuzzer's finding: the input that made a reader throw something undocumented.
void abortOnCrash(const Outcome& outcome) {
  if (outcome.kind != OutcomeClass::crashed) return;
  std::fprintf(stderr, "fuzz harness: %s\n", outcome.text.c_str());
  std::abort();
}

Outcome vegOutcome(const std::uint8_t* data, std::size_t size) {
  return readMesh([&] { return writeInput("input.veg", data, size); }, readVeg);
}

Outcome tetGenOutcome(const std::uint8_t* data, std::size_t size) {
  return readMesh(
      [&] {
        const std::string_view text(reinterpret_cast<const char*>(data), size);
        constexpr std::string_view separator = "@@ele\n";
        std::size_t split = text.find(separator);
        const std::size_t eleStart = split == std::string_view::npos ? size : split + separator.size();
        if (split == std::string_view::npos) split = size;
        writeInput("input.ele", data + eleStart, size - eleStart);
        return writeInput("input.node", data, split);
      },
      readTetGen);
}

Outcome gmshOutcome(const std::uint8_t* data, std::size_t size) {
  return readMesh([&] { return writeInput("input.msh", data, size); }, readGmsh);
}

Outcome simulationReaderOutcome(const std::uint8_t* data, std::size_t size) {
  std::string badFrames;
  Outcome outcome = classify([&] {
    SimulationReader reader(writeInput("input.afsim", data, size));
    SimulationFrame frame;
    std::int64_t good = 0;
    for (std::int64_t k = 0; k < reader.numFrames(); ++k) {
      try {
        reader.readFrame(k, frame);
        ++good;
      } catch (const ParseError& error) {
        // A corrupted record is reported; the reader stays usable for the others.
        badFrames += "; frame " + std::to_string(k) + ": " + describe(error);
      }
    }
    return std::to_string(reader.numVertices()) + " vertices, " + std::to_string(good) + " of " +
           std::to_string(reader.numFrames()) + " frames read" + badFrames;
  });
  if (outcome.kind == OutcomeClass::accepted && !badFrames.empty()) outcome.kind = OutcomeClass::rejected;
  return outcome;
}

Outcome checkpointOutcome(const std::uint8_t* data, std::size_t size) {
  return classify([&] {
    const SimulationCheckpoint checkpoint = parseCheckpoint(data, size, "input.checkpoint");
    if (checkpoint.displacement.size() != checkpoint.velocity.size()) std::abort();
    return checkpoint.integrator + ", " + std::to_string(checkpoint.frames) + " frames, " +
           std::to_string(checkpoint.displacement.size()) + " state entries";
  });
}

int fuzzVeg(const std::uint8_t* data, std::size_t size) {
  abortOnCrash(vegOutcome(data, size));
  return 0;
}

int fuzzTetGen(const std::uint8_t* data, std::size_t size) {
  abortOnCrash(tetGenOutcome(data, size));
  return 0;
}

int fuzzGmsh(const std::uint8_t* data, std::size_t size) {
  abortOnCrash(gmshOutcome(data, size));
  return 0;
}

int fuzzSimulationFile(const std::uint8_t* data, std::size_t size) {
  abortOnCrash(simulationReaderOutcome(data, size));
  abortOnCrash(checkpointOutcome(data, size));
  return 0;
}

std::vector<Harness> fileHarnesses() {
  return {{"veg", {{"veg", vegOutcome}}},
          {"tetgen", {{"tetgen", tetGenOutcome}}},
          {"gmsh", {{"gmsh", gmshOutcome}}},
          {"simulationFile", {{"simulationReader", simulationReaderOutcome}, {"checkpoint", checkpointOutcome}}}};
}

}  // namespace asyncfem::fuzz
