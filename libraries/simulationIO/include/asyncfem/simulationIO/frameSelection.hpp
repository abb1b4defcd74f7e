// SPDX-License-Identifier: BSD-3-Clause
// Which frames of a simulation file a tool reads (frameRenderer --frames, afsimTool --frames).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace asyncfem::frames {

/// A Python-style slice start:stop:step of frame indices (stop exclusive). Empty fields
/// take defaults: start 0, stop = the number of frames, step 1; a single number N means
/// the one frame N.
struct FrameSlice {
  std::int64_t start = 0;
  std::int64_t stop = -1;  ///< -1: up to the last frame
  std::int64_t step = 1;
};

/// Comma-separated slices, e.g. "10,20" (frames 10 and 20), "0:100:10,150". Empty text
/// selects every frame.
struct FrameSelection {
  std::string text;  ///< as given, for messages
  std::vector<FrameSlice> slices;
};

/// Parses "start:stop:step[,start:stop:step...]" (see FrameSelection). Throws
/// asyncfem::Error naming the text for malformed numbers, negative values or a step < 1.
FrameSelection parseFrameSelection(const std::string& text);

/// The frame indices of selection in a file of numFrames frames, slice after slice, in
/// the order given. Throws asyncfem::Error when a slice reaches beyond the file ("frames
/// 0:200:5: stop 200 is beyond the 120 frames of FILE (frames 0 to 119)") or selects
/// nothing.
std::vector<std::int64_t> selectFrames(const FrameSelection& selection, std::int64_t numFrames,
                                       const std::string& fileName);

}  // namespace asyncfem::frames
