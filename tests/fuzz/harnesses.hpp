// SPDX-License-Identifier: BSD-3-Clause
// Fuzz harnesses: one entry function per input format. libFuzzer calls them through
// LLVMFuzzerTestOneInput (fuzzEntry.cpp.in, ASYNCFEM_FUZZ=ON); the normal build runs
// them over the seed corpus in tests/fuzz/corpus (fuzzCorpusTest.cpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace asyncfem::fuzz {

/// What a reader made of one input.
enum class OutcomeClass {
  accepted,  ///< read without an error
  rejected,  ///< refused with an asyncfem::Error: the documented outcome of bad input
  crashed,   ///< another exception escaped the reader: a finding (a real crash ends the process)
};

/// The class and a one-line summary: "accepted": what was read ("5 vertices, 2 elements");
/// "rejected": "ErrorClass: message" (ErrorClass: ParseError, ValidationError,
/// TimestepError, NumericalError or Error) with the scratch folder the input went through
/// written as "<scratch>"; "crashed": the exception's type and message.
struct Outcome {
  OutcomeClass kind = OutcomeClass::crashed;
  std::string text;
};

/// One reader of outside input, fed the bytes through a file in a scratch folder.
/// veg: .veg text (readVeg). tetgen: a TetGen pair, the bytes before the first line "@@ele"
/// the .node file and the rest the .ele file (readTetGen). gmsh: Gmsh .msh text (readGmsh).
/// simulationReader: a simulation output file, its header and every frame
/// (SimulationReader; rejected when the header or any frame is). checkpoint: the same
/// bytes as a checkpoint (parseCheckpoint). scene: JSON scene text (loadScene; small box
/// meshes are built too, buildSimulation).
Outcome vegOutcome(const std::uint8_t* data, std::size_t size);
Outcome tetGenOutcome(const std::uint8_t* data, std::size_t size);
Outcome gmshOutcome(const std::uint8_t* data, std::size_t size);
Outcome simulationReaderOutcome(const std::uint8_t* data, std::size_t size);
Outcome checkpointOutcome(const std::uint8_t* data, std::size_t size);
Outcome sceneOutcome(const std::uint8_t* data, std::size_t size);

/// The libFuzzer entry of each harness (LLVMFuzzerTestOneInput, fuzzEntry.cpp.in,
/// ASYNCFEM_FUZZ=ON): runs its readers and aborts on a "crashed" outcome, so that libFuzzer
/// records the input; returns 0, as libFuzzer expects. fuzzSimulationFile runs both the
/// simulationReader and the checkpoint reader.
int fuzzVeg(const std::uint8_t* data, std::size_t size);
int fuzzTetGen(const std::uint8_t* data, std::size_t size);
int fuzzGmsh(const std::uint8_t* data, std::size_t size);
int fuzzSimulationFile(const std::uint8_t* data, std::size_t size);
int fuzzScene(const std::uint8_t* data, std::size_t size);

/// A reader by name, for the corpus replay (fuzzCorpusTest.cpp).
struct Reader {
  std::string name;
  Outcome (*outcome)(const std::uint8_t*, std::size_t);
};

/// A harness by name ("veg", "tetgen", "gmsh", "simulationFile", "scene"; the name of its
/// seed folder tests/fuzz/corpus/<name>) and the readers its libFuzzer entry runs.
struct Harness {
  std::string name;
  std::vector<Reader> readers;
};
/// Every harness (sceneHarness.cpp).
std::vector<Harness> allHarnesses();
/// The harnesses of the mesh and output-file readers, without the scene (harnesses.cpp):
/// they need only volumetricMesh and simulationIO, so the sanitized library build of
/// scripts/run-tests.sh replays their corpora (fuzzFileCorpusTests).
std::vector<Harness> fileHarnesses();

}  // namespace asyncfem::fuzz
