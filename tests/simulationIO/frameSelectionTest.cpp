// SPDX-License-Identifier: BSD-3-Clause
// --frames selections: slices, single frames, comma lists, and their errors.
#include <gtest/gtest.h>

#include <asyncfem/core/error.hpp>
#include <asyncfem/simulationIO/frameSelection.hpp>
#include <string>
#include <vector>

namespace {

using asyncfem::frames::parseFrameSelection;
using asyncfem::frames::selectFrames;
using Frames = std::vector<std::int64_t>;

Frames select(const std::string& text, std::int64_t numFrames) {
  return selectFrames(parseFrameSelection(text), numFrames, "run.afsim");
}

std::string errorOf(const std::string& text, std::int64_t numFrames) {
  try {
    select(text, numFrames);
  } catch (const asyncfem::Error& error) {
    return error.what();
  }
  return "no error";
}

TEST(FrameSelection, SlicesSingleFramesAndLists) {
  EXPECT_EQ(select("", 4), (Frames{0, 1, 2, 3}));
  EXPECT_EQ(select("0:", 3), (Frames{0, 1, 2}));
  EXPECT_EQ(select(":2", 5), (Frames{0, 1}));
  EXPECT_EQ(select("1:8:3", 10), (Frames{1, 4, 7}));
  EXPECT_EQ(select("7", 10), (Frames{7}));
  EXPECT_EQ(select("10,20", 21), (Frames{10, 20}));
  EXPECT_EQ(select("0:4:2,9,5:7", 10), (Frames{0, 2, 9, 5, 6}));
}

TEST(FrameSelection, ErrorsNameTheSelectionAndTheFile) {
  EXPECT_EQ(errorOf("0:20:5", 6), "frames 0:20:5: stop 20 is beyond the 6 frames of run.afsim (frames 0 to 5)");
  EXPECT_EQ(errorOf("1,6", 6), "frames 1,6: start 6 is beyond the 6 frames of run.afsim (frames 0 to 5)");
  EXPECT_EQ(errorOf("3:3", 6), "frames 3:3: selects no frame (stop must be greater than start)");
  EXPECT_NE(errorOf("a:b", 6).find("\"a\" is not a frame number"), std::string::npos);
  EXPECT_NE(errorOf("1,,2", 6).find("empty item"), std::string::npos);
  EXPECT_NE(errorOf("0:4:0", 6).find("the step must be at least 1"), std::string::npos);
  EXPECT_NE(errorOf("1:2:3:4", 6).find("expected start:stop:step"), std::string::npos);
}

}  // namespace
