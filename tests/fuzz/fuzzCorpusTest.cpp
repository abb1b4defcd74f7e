// SPDX-License-Identifier: BSD-3-Clause
// Runs every fuzz harness over its seed corpus (tests/fuzz/corpus/<harness>/), so the
// harnesses are compiled and exercised by the normal test suite. The corpus holds valid
// files plus every input that once crashed, hung or over-allocated (named crash-* or
// oom-* or timeout-*), so this is also the regression test for those fixes.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <ostream>
#include <string>
#include <vector>

#include "harnesses.hpp"

namespace asyncfem::fuzz {
// GoogleTest prints a test's parameter next to its name: print the harness's name rather
// than the raw bytes of the struct.
void PrintTo(const Harness& harness, std::ostream* out) { *out << harness.name; }
}  // namespace asyncfem::fuzz

namespace {

namespace fs = std::filesystem;

std::vector<std::uint8_t> readBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

class FuzzCorpusTest : public ::testing::TestWithParam<asyncfem::fuzz::Harness> {};

TEST_P(FuzzCorpusTest, EveryCorpusInputIsHandled) {
  const asyncfem::fuzz::Harness& harness = GetParam();
  const fs::path folder = fs::path(ASYNCFEM_FUZZ_CORPUS_DIR) / harness.name;
  ASSERT_TRUE(fs::is_directory(folder)) << folder;
  std::vector<fs::path> inputs;
  for (const fs::directory_entry& entry : fs::directory_iterator(folder)) {
    if (entry.is_regular_file()) inputs.push_back(entry.path());
  }
  std::sort(inputs.begin(), inputs.end());
  ASSERT_FALSE(inputs.empty()) << "no seed inputs in " << folder;
  for (const fs::path& input : inputs) {
    SCOPED_TRACE(input.string());
    const std::vector<std::uint8_t> bytes = readBytes(input);
    // Harnesses swallow the documented errors; anything else escapes and fails here.
    EXPECT_EQ(harness.function(bytes.data(), bytes.size()), 0);
  }
}

INSTANTIATE_TEST_SUITE_P(Harnesses, FuzzCorpusTest, ::testing::ValuesIn(asyncfem::fuzz::allHarnesses()),
                         [](const ::testing::TestParamInfo<asyncfem::fuzz::Harness>& info) { return info.param.name; });

}  // namespace
