// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// What the end-to-end tests of the utilities share: a scratch folder per test and running
// an executable of ASYNCFEM_BIN_DIR with its stdout and stderr captured separately.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace asyncfem::test {

struct RunResult {
  int exitCode = -1;
  std::string out;
  std::string err;
};

inline std::string readText(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

/// In a forked child: replaces the process with command[0] run with the arguments
/// command[1..]; exits with status 127 if that fails.
[[noreturn]] inline void execCommand(std::vector<std::string> command) {
  std::vector<char*> argv;
  for (std::string& argument : command) argv.push_back(argument.data());
  argv.push_back(nullptr);
  ::execv(argv[0], argv.data());
  ::_exit(127);
}

/// A fixture with a fresh folder_ (removed after the test) named after the test.
class UtilityTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    folder_ = std::filesystem::temp_directory_path() / ("asyncfem-" + std::string(info->test_suite_name()) + "-" +
                                                        std::string(info->name()) + "-" + std::to_string(::getpid()));
    std::filesystem::remove_all(folder_);
    std::filesystem::create_directories(folder_);
  }
  void TearDown() override { std::filesystem::remove_all(folder_); }

  /// Runs the shell command `commandLine` (already quoted) with stdout and stderr to files
  /// (so stderr is not a terminal) and stdin from /dev/null.
  RunResult runCommand(const std::string& commandLine) const {
    const std::filesystem::path out = folder_ / "stdout.txt";
    const std::filesystem::path err = folder_ / "stderr.txt";
    const std::string command = commandLine + " > '" + out.string() + "' 2> '" + err.string() + "' < /dev/null";
    const int status = std::system(command.c_str());
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, readText(out), readText(err)};
  }

  std::filesystem::path folder_;
};

}  // namespace asyncfem::test
