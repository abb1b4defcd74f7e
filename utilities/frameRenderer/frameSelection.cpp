// SPDX-License-Identifier: BSD-3-Clause
#include "frameSelection.hpp"

#include <asyncfem/core/error.hpp>
#include <charconv>

namespace asyncfem::frames {

namespace {

std::int64_t parseField(const std::string& field, const std::string& text, std::int64_t fallback) {
  if (field.empty()) {
    return fallback;
  }
  std::int64_t value = 0;
  const auto [end, error] = std::from_chars(field.data(), field.data() + field.size(), value);
  if (error != std::errc() || end != field.data() + field.size() || value < 0) {
    throw Error("--frames " + text + ": \"" + field +
                "\" is not a frame number (expected start:stop:step with integers >= 0)");
  }
  return value;
}

}  // namespace

FrameSelection parseFrameSelection(const std::string& text) {
  std::vector<std::string> fields{""};
  for (const char c : text) {
    if (c == ':') {
      fields.emplace_back();
    } else {
      fields.back() += c;
    }
  }
  if (fields.size() > 3) {
    throw Error("--frames " + text + ": expected start:stop:step");
  }
  FrameSelection selection;
  selection.text = text;
  selection.start = parseField(fields[0], text, 0);
  if (fields.size() == 1) {
    if (fields[0].empty()) {
      return selection;  // everything
    }
    selection.stop = selection.start + 1;
    return selection;
  }
  selection.stop = parseField(fields[1], text, -1);
  if (fields.size() == 3) {
    selection.step = parseField(fields[2], text, 1);
    if (selection.step < 1) {
      throw Error("--frames " + text + ": the step must be at least 1");
    }
  }
  return selection;
}

std::vector<std::int64_t> selectFrames(const FrameSelection& selection, std::int64_t numFrames,
                                       const std::string& fileName) {
  const std::string range = numFrames > 0 ? " (frames 0 to " + std::to_string(numFrames - 1) + ")" : "";
  const std::string what = selection.text.empty() ? "frames" : "frames " + selection.text;
  const std::int64_t stop = selection.stop < 0 ? numFrames : selection.stop;
  if (selection.start >= numFrames) {
    throw Error(what + ": start " + std::to_string(selection.start) + " is beyond the " + std::to_string(numFrames) +
                " frames of " + fileName + range);
  }
  if (stop > numFrames) {
    throw Error(what + ": stop " + std::to_string(stop) + " is beyond the " + std::to_string(numFrames) +
                " frames of " + fileName + range);
  }
  std::vector<std::int64_t> frames;
  for (std::int64_t k = selection.start; k < stop; k += selection.step) {
    frames.push_back(k);
  }
  if (frames.empty()) {
    throw Error(what + ": selects no frame (stop must be greater than start)");
  }
  return frames;
}

}  // namespace asyncfem::frames
