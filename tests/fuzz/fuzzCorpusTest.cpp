// SPDX-License-Identifier: BSD-3-Clause
// Runs every fuzz harness over its seed corpus (tests/fuzz/corpus/<harness>/) and compares
// what the reader made of each seed with the expectation stored for it in
// tests/fuzz/corpus/<harness>.expected: accepted (with a summary of what was read) or
// rejected with the exact error class and message. The corpus holds valid files plus
// every input that once crashed, hung or over-allocated (named crash-* or oom-* or
// timeout-*), so this is also the regression test for those fixes.
//
// A seed added to a corpus needs its line in the .expected file: run the test with
// ASYNCFEM_FUZZ_WRITE_EXPECTED=1 to rewrite the files from the current outcomes (the test
// then reports itself skipped), and review the diff.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <ostream>
#include <sstream>
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

// One line per outcome: newlines and backslashes escaped, so that every seed is one line
// "SEED<TAB>OUTCOME" of the manifest.
std::string escape(const std::string& text) {
  std::string escaped;
  for (const char c : text) {
    if (c == '\\') {
      escaped += "\\\\";
    } else if (c == '\n') {
      escaped += "\\n";
    } else if (c == '\t') {
      escaped += "\\t";
    } else {
      escaped += c;
    }
  }
  return escaped;
}

const char* manifestHeader =
    "# Expected outcome of every seed in the folder of the same name: SEED<TAB>OUTCOME, one line each\n"
    "# (newlines in messages as \\n). Checked by fuzzCorpusTests; rewrite with\n"
    "# ASYNCFEM_FUZZ_WRITE_EXPECTED=1 build/bin/fuzzCorpusTests and review the diff.\n";

std::map<std::string, std::string> readManifest(const fs::path& path) {
  std::map<std::string, std::string> expected;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    const std::size_t tab = line.find('\t');
    if (tab == std::string::npos) {
      ADD_FAILURE() << path.string() << ": line without a tab: " << line;
      continue;
    }
    const bool inserted = expected.emplace(line.substr(0, tab), line.substr(tab + 1)).second;
    EXPECT_TRUE(inserted) << path.string() << ": seed listed twice: " << line.substr(0, tab);
  }
  return expected;
}

class FuzzCorpusTest : public ::testing::TestWithParam<asyncfem::fuzz::Harness> {};

TEST_P(FuzzCorpusTest, EverySeedHasItsExpectedOutcome) {
  const asyncfem::fuzz::Harness& harness = GetParam();
  const fs::path folder = fs::path(ASYNCFEM_FUZZ_CORPUS_DIR) / harness.name;
  const fs::path manifest = fs::path(ASYNCFEM_FUZZ_CORPUS_DIR) / (harness.name + ".expected");
  ASSERT_TRUE(fs::is_directory(folder)) << folder;
  std::vector<fs::path> inputs;
  for (const fs::directory_entry& entry : fs::directory_iterator(folder)) {
    if (entry.is_regular_file()) inputs.push_back(entry.path());
  }
  std::sort(inputs.begin(), inputs.end());
  ASSERT_FALSE(inputs.empty()) << "no seed inputs in " << folder;

  std::map<std::string, std::string> outcomes;
  for (const fs::path& input : inputs) {
    const std::vector<std::uint8_t> bytes = readBytes(input);
    // Harnesses catch the documented errors; anything else escapes and fails here.
    EXPECT_EQ(harness.function(bytes.data(), bytes.size()), 0) << input;
    outcomes[input.filename().string()] = escape(harness.outcome(bytes.data(), bytes.size()));
  }

  const char* write = std::getenv("ASYNCFEM_FUZZ_WRITE_EXPECTED");
  if (write != nullptr && std::string(write) == "1") {
    std::ofstream out(manifest);
    out << manifestHeader;
    for (const auto& [seed, outcome] : outcomes) out << seed << '\t' << outcome << '\n';
    GTEST_SKIP() << "rewrote " << manifest.string() << " (" << outcomes.size() << " seeds); review the diff";
  }

  ASSERT_TRUE(fs::is_regular_file(manifest)) << "no expectations: " << manifest.string();
  const std::map<std::string, std::string> expected = readManifest(manifest);
  for (const auto& [seed, outcome] : outcomes) {
    const auto found = expected.find(seed);
    if (found == expected.end()) {
      ADD_FAILURE() << manifest.string() << " has no line for the seed " << seed << "; its outcome is:\n"
                    << seed << '\t' << outcome;
      continue;
    }
    EXPECT_EQ(outcome, found->second) << "seed " << (folder / seed).string();
  }
  for (const auto& [seed, outcome] : expected) {
    EXPECT_TRUE(outcomes.count(seed) == 1)
        << manifest.string() << " lists " << seed << ", which is not in " << folder.string();
  }
}

INSTANTIATE_TEST_SUITE_P(Harnesses, FuzzCorpusTest, ::testing::ValuesIn(asyncfem::fuzz::allHarnesses()),
                         [](const ::testing::TestParamInfo<asyncfem::fuzz::Harness>& info) { return info.param.name; });

}  // namespace
