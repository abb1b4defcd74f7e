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

/// Every harness: feeds the bytes to one reader. Errors the reader documents
/// (asyncfem::Error and its subclasses) are the expected outcome for bad input and are
/// swallowed; anything else (another exception, a crash, a sanitizer report, a hang, a
/// huge allocation) is a finding. Returns 0, as libFuzzer expects.
///
/// .veg text (readVeg).
int fuzzVeg(const std::uint8_t* data, std::size_t size);
/// TetGen pair: the bytes before the first line "@@ele" are the .node file, the rest
/// the .ele file (readTetGen).
int fuzzTetGen(const std::uint8_t* data, std::size_t size);
/// Gmsh .msh text (readGmsh).
int fuzzGmsh(const std::uint8_t* data, std::size_t size);
/// A simulation output file (SimulationReader: header, every frame) and the same bytes
/// as a checkpoint (parseCheckpoint).
int fuzzSimulationFile(const std::uint8_t* data, std::size_t size);
/// JSON scene text (nlohmann::json::parse, then parseScene).
int fuzzScene(const std::uint8_t* data, std::size_t size);

/// What each harness made of an input, as one line for the corpus replay (the expected
/// outcome of every seed is stored in tests/fuzz/corpus/<harness>.expected):
/// "accepted: ..." with a summary of what was read, or "rejected: <ErrorClass>: <message>"
/// (ErrorClass: ParseError, ValidationError, TimestepError, NumericalError or Error),
/// with the scratch folder the input went through written as "<scratch>". The fuzz*
/// functions above call these and discard the text.
std::string vegOutcome(const std::uint8_t* data, std::size_t size);
std::string tetGenOutcome(const std::uint8_t* data, std::size_t size);
std::string gmshOutcome(const std::uint8_t* data, std::size_t size);
/// "reader: ...; frame K: ...(each frame that is rejected); checkpoint: ...".
std::string simulationFileOutcome(const std::uint8_t* data, std::size_t size);
/// "not JSON: <parser message>", or the outcome of parseScene.
std::string sceneOutcome(const std::uint8_t* data, std::size_t size);

/// A harness by name: "veg", "tetgen", "gmsh", "simulationFile", "scene".
struct Harness {
  std::string name;
  int (*function)(const std::uint8_t*, std::size_t);
  std::string (*outcome)(const std::uint8_t*, std::size_t);
};
std::vector<Harness> allHarnesses();

}  // namespace asyncfem::fuzz
