// SPDX-License-Identifier: BSD-3-Clause
// Runs every fuzz harness's readers over its seed corpus (tests/fuzz/corpus/<harness>/) and
// compares each outcome with the expectation written beside the corpus in
// tests/fuzz/corpus/<harness>.expected from how the seed was built: its class (accepted
// or rejected, never crashed) and a text the reader's summary must contain (what it read,
// or the place and rule the error names), with the reason. The corpus holds valid files
// plus every input that once crashed, hung or over-allocated (named crash-* or oom-* or
// timeout-*), so this is also the regression test for those fixes.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
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
using asyncfem::fuzz::Harness;
using asyncfem::fuzz::Outcome;
using asyncfem::fuzz::OutcomeClass;
using asyncfem::fuzz::Reader;

std::vector<std::uint8_t> readBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

const char* className(OutcomeClass kind) {
  switch (kind) {
    case OutcomeClass::accepted:
      return "accepted";
    case OutcomeClass::rejected:
      return "rejected";
    case OutcomeClass::crashed:
      return "crashed";
  }
  return "?";
}

// One line of a .expected file: "SEED | READER | CLASS | TEXT | WHY".
struct Expectation {
  std::string reader;
  std::string kind;
  std::string text;
  std::string why;
};

std::vector<std::string> splitFields(const std::string& line) {
  const std::string separator = " | ";
  std::vector<std::string> fields;
  std::size_t start = 0;
  for (std::size_t at = line.find(separator); at != std::string::npos; at = line.find(separator, start)) {
    fields.push_back(line.substr(start, at - start));
    start = at + separator.size();
  }
  fields.push_back(line.substr(start));
  return fields;
}

std::map<std::string, Expectation> readExpectations(const fs::path& path) {
  std::map<std::string, Expectation> expected;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    const std::vector<std::string> fields = splitFields(line);
    if (fields.size() != 5 || fields[4].empty()) {
      ADD_FAILURE() << path.string() << ": not SEED | READER | CLASS | TEXT | WHY: " << line;
      continue;
    }
    EXPECT_TRUE(fields[2] == "accepted" || fields[2] == "rejected") << path.string() << ": " << line;
    EXPECT_FALSE(fields[3].empty()) << path.string() << ": no text to look for: " << line;
    const bool inserted = expected.emplace(fields[0], Expectation{fields[1], fields[2], fields[3], fields[4]}).second;
    EXPECT_TRUE(inserted) << path.string() << ": seed listed twice: " << fields[0];
  }
  return expected;
}

class FuzzCorpusTest : public ::testing::TestWithParam<Harness> {};

TEST_P(FuzzCorpusTest, EverySeedHasItsExpectedOutcome) {
  const Harness& harness = GetParam();
  const fs::path folder = fs::path(ASYNCFEM_FUZZ_CORPUS_DIR) / harness.name;
  const fs::path manifest = fs::path(ASYNCFEM_FUZZ_CORPUS_DIR) / (harness.name + ".expected");
  ASSERT_TRUE(fs::is_directory(folder)) << folder;
  ASSERT_TRUE(fs::is_regular_file(manifest)) << "no expectations: " << manifest.string();
  const std::map<std::string, Expectation> expected = readExpectations(manifest);

  std::vector<fs::path> inputs;
  for (const fs::directory_entry& entry : fs::directory_iterator(folder)) {
    if (entry.is_regular_file()) inputs.push_back(entry.path());
  }
  std::sort(inputs.begin(), inputs.end());
  ASSERT_FALSE(inputs.empty()) << "no seed inputs in " << folder;

  for (const fs::path& input : inputs) {
    const std::string seed = input.filename().string();
    const auto found = expected.find(seed);
    if (found == expected.end()) {
      ADD_FAILURE() << manifest.string() << " has no line for the seed " << seed
                    << ": add one saying, from how the seed is built, what it must do and why";
      continue;
    }
    const Expectation& expectation = found->second;
    const std::vector<std::uint8_t> bytes = readBytes(input);
    bool readerFound = false;
    for (const Reader& reader : harness.readers) {
      const Outcome outcome = reader.outcome(bytes.data(), bytes.size());
      // No input may make a reader throw what it does not document (or crash the process).
      EXPECT_NE(outcome.kind, OutcomeClass::crashed) << input.string() << " (" << reader.name << "): " << outcome.text;
      if (reader.name != expectation.reader) {
        // The harness's other readers are for another format (a different magic number).
        EXPECT_EQ(outcome.kind, OutcomeClass::rejected)
            << input.string() << " is not a " << reader.name << " input, yet: " << outcome.text;
        continue;
      }
      readerFound = true;
      EXPECT_EQ(className(outcome.kind), expectation.kind)
          << input.string() << " (" << expectation.why << "): " << outcome.text;
      EXPECT_NE(outcome.text.find(expectation.text), std::string::npos)
          << input.string() << " (" << expectation.why << "): expected the text \"" << expectation.text
          << "\" in: " << outcome.text;
    }
    EXPECT_TRUE(readerFound) << manifest.string() << ": " << seed << ": harness " << harness.name << " has no reader "
                             << expectation.reader;
  }
  for (const auto& [seed, expectation] : expected) {
    EXPECT_TRUE(fs::is_regular_file(folder / seed))
        << manifest.string() << " lists " << seed << ", which is not in " << folder.string();
  }
}

// ASYNCFEM_FUZZ_REPLAYED_HARNESSES: allHarnesses (fuzzCorpusTests) or fileHarnesses
// (fuzzFileCorpusTests, for the sanitized build without sceneIO; tests/fuzz/CMakeLists.txt).
INSTANTIATE_TEST_SUITE_P(Harnesses, FuzzCorpusTest,
                         ::testing::ValuesIn(asyncfem::fuzz::ASYNCFEM_FUZZ_REPLAYED_HARNESSES()),
                         [](const ::testing::TestParamInfo<Harness>& info) { return info.param.name; });

}  // namespace
