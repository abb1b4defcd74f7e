// SPDX-License-Identifier: BSD-3-Clause
// Runs a built utility as a user would and captures what it prints (end-to-end tests).
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace asyncfem::test {

/// Exit status (-1 if the process did not exit normally), stdout and stderr of one run.
struct RunResult {
  int exitCode = -1;
  std::string out;
  std::string err;
};

/// An empty folder for the running test: TMP/asyncfem-<tool>-<test name>-<pid>.
inline std::filesystem::path freshTestFolder(const std::string& tool) {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::filesystem::path folder = std::filesystem::temp_directory_path() /
                                       ("asyncfem-" + tool + "-" + info->name() + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(folder);
  std::filesystem::create_directories(folder);
  return folder;
}

/// The whole file as bytes (empty if it cannot be read).
inline std::string readText(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

/// Runs `'executable' arguments` (arguments shell-quoted by the caller) through the shell,
/// in workingDirectory when one is given, with stdin from /dev/null and stdout and stderr
/// in scratch/stdout.txt and scratch/stderr.txt (files, so stderr is not a terminal).
inline RunResult runTool(const std::string& executable, const std::string& arguments,
                         const std::filesystem::path& scratch, const std::filesystem::path& workingDirectory = {}) {
  const std::filesystem::path out = scratch / "stdout.txt";
  const std::filesystem::path err = scratch / "stderr.txt";
  std::string command = workingDirectory.empty() ? "" : "cd '" + workingDirectory.string() + "' && ";
  command += "'" + executable + "' " + arguments + " > '" + out.string() + "' 2> '" + err.string() + "' < /dev/null";
  const int status = std::system(command.c_str());
  RunResult result;
  result.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  result.out = readText(out);
  result.err = readText(err);
  return result;
}

}  // namespace asyncfem::test
