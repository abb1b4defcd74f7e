// SPDX-License-Identifier: BSD-3-Clause
// Shared pieces of the sceneIO tests: a small valid scene and a scratch folder.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

namespace asyncfem::test {

/// A valid scene on a 2 x 1 x 1 box of 2 x 1 x 1 cells (12 vertices), fixed at x = 0,
/// backward Euler with 10 steps per frame.
inline nlohmann::json smallScene() {
  return nlohmann::json::parse(R"({
    "mesh": {"generator": "box", "size": [2, 1, 1], "cells": [2, 1, 1],
             "material": {"name": "rubber", "density": 1000, "youngsModulus": 1e5, "poissonRatio": 0.4}},
    "fixed": {"sets": ["xmin"]},
    "integrator": {"name": "backward-euler", "timestep": 0.01},
    "frames": {"rate": 10, "count": 3}
  })");
}

/// A fresh folder under the system temporary folder, removed when the test ends.
class ScratchFolder {
 public:
  ScratchFolder() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = std::filesystem::temp_directory_path() / ("asyncfem-" + std::string(info->test_suite_name()) + "-" +
                                                      std::string(info->name()) + "-" + std::to_string(::getpid()));
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~ScratchFolder() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  ScratchFolder(const ScratchFolder&) = delete;
  ScratchFolder& operator=(const ScratchFolder&) = delete;

  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path write(const std::string& name, const std::string& text) const {
    const std::filesystem::path file = path_ / name;
    std::filesystem::create_directories(file.parent_path());
    std::ofstream(file) << text;
    return file;
  }

 private:
  std::filesystem::path path_;
};

}  // namespace asyncfem::test
