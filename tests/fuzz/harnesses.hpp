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

/// A harness by name: "veg", "tetgen", "gmsh", "simulationFile", "scene".
struct Harness {
  std::string name;
  int (*function)(const std::uint8_t*, std::size_t);
};
std::vector<Harness> allHarnesses();

}  // namespace asyncfem::fuzz
