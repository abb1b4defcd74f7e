// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/core/error.hpp>
#include <asyncfem/simulationIO/frameSelection.hpp>
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

FrameSlice parseSlice(const std::string& slice, const std::string& text) {
  std::vector<std::string> fields{""};
  for (const char c : slice) {
    if (c == ':') {
      fields.emplace_back();
    } else {
      fields.back() += c;
    }
  }
  if (fields.size() > 3) {
    throw Error("--frames " + text + ": expected start:stop:step");
  }
  FrameSlice result;
  result.start = parseField(fields[0], text, 0);
  if (fields.size() == 1) {
    if (fields[0].empty()) {
      throw Error("--frames " + text + ": empty item (expected start:stop:step or a frame number)");
    }
    result.stop = result.start + 1;
    return result;
  }
  result.stop = parseField(fields[1], text, -1);
  if (fields.size() == 3) {
    result.step = parseField(fields[2], text, 1);
    if (result.step < 1) {
      throw Error("--frames " + text + ": the step must be at least 1");
    }
  }
  return result;
}

}  // namespace

FrameSelection parseFrameSelection(const std::string& text) {
  FrameSelection selection;
  selection.text = text;
  if (text.empty()) {
    selection.slices.emplace_back();  // everything
    return selection;
  }
  std::string item;
  for (std::size_t i = 0; i <= text.size(); ++i) {
    if (i == text.size() || text[i] == ',') {
      selection.slices.push_back(parseSlice(item, text));
      item.clear();
    } else {
      item += text[i];
    }
  }
  return selection;
}

std::vector<std::int64_t> selectFrames(const FrameSelection& selection, std::int64_t numFrames,
                                       const std::string& fileName) {
  const std::string range = numFrames > 0 ? " (frames 0 to " + std::to_string(numFrames - 1) + ")" : "";
  const std::string what = selection.text.empty() ? "frames" : "frames " + selection.text;
  std::vector<std::int64_t> frames;
  for (const FrameSlice& slice : selection.slices) {
    const std::int64_t stop = slice.stop < 0 ? numFrames : slice.stop;
    if (slice.start >= numFrames) {
      throw Error(what + ": start " + std::to_string(slice.start) + " is beyond the " + std::to_string(numFrames) +
                  " frames of " + fileName + range);
    }
    if (stop > numFrames) {
      throw Error(what + ": stop " + std::to_string(stop) + " is beyond the " + std::to_string(numFrames) +
                  " frames of " + fileName + range);
    }
    if (stop <= slice.start) {
      throw Error(what + ": selects no frame (stop must be greater than start)");
    }
    for (std::int64_t k = slice.start; k < stop; k += slice.step) {
      frames.push_back(k);
    }
  }
  return frames;
}

}  // namespace asyncfem::frames
