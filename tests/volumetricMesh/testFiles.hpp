// SPDX-License-Identifier: BSD-3-Clause
// Helpers for the volumetricMesh tests: a scratch folder per test and file writing.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <asyncfem/core/error.hpp>
#include <filesystem>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <string>
#include <string_view>

namespace asyncfem::test {

/// A fresh folder under the system temp directory, removed when the test ends.
class ScratchDir {
 public:
  ScratchDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = std::filesystem::temp_directory_path() / ("asyncfem-mesh-" + std::string(info->test_suite_name()) + "-" +
                                                     info->name() + "-" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  ~ScratchDir() {
    std::error_code ignored;
    std::filesystem::remove_all(dir_, ignored);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;

  const std::filesystem::path& path() const { return dir_; }
  /// Writes text (bytes exactly as given) to name inside the folder and returns its path.
  std::filesystem::path write(const std::string& name, std::string_view text) const {
    const std::filesystem::path p = dir_ / name;
    std::ofstream out(p, std::ios::binary);
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
    return p;
  }

 private:
  std::filesystem::path dir_;
};

/// Runs read, expects a ParseError whose file() ends with fileName, whose line() is line,
/// whose message starts with "FILE:LINE:" and contains every one of the fragments.
inline void expectParseError(const std::function<void()>& read, const std::string& fileName, std::size_t line,
                             std::initializer_list<std::string> fragments) {
  try {
    read();
    ADD_FAILURE() << "expected a ParseError from " << fileName << ":" << line;
  } catch (const ParseError& e) {
    const std::string message = e.what();
    EXPECT_EQ(std::filesystem::path(e.file()).filename().string(), fileName) << message;
    EXPECT_EQ(e.line(), line) << message;
    if (line > 0) {
      EXPECT_NE(message.find(fileName + ":" + std::to_string(line) + ": "), std::string::npos) << message;
    }
    for (const std::string& fragment : fragments) {
      EXPECT_NE(message.find(fragment), std::string::npos) << "'" << fragment << "' missing from: " << message;
    }
  }
}

/// Two positively oriented tetrahedra sharing the face (2, 3, 4), in .veg form.
inline constexpr std::string_view kTwoTetVertices =
    "*VERTICES\n"
    "5 3 0 0\n"
    "1 0 0 0\n"
    "2 1 0 0\n"
    "3 0 1 0\n"
    "4 0 0 1\n"
    "5 1 1 1\n";
inline constexpr std::string_view kTwoTetElements =
    "*ELEMENTS\n"
    "TET\n"
    "2 4 0\n"
    "1 1 2 3 4\n"
    "2 2 3 4 5\n";
inline constexpr std::string_view kSteelRegion =
    "*MATERIAL steel\n"
    "ENU, 7800, 2e11, 0.3\n"
    "*REGION\n"
    "allElements, steel\n";

}  // namespace asyncfem::test
