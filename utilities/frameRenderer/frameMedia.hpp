// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// What frameRenderer makes of the frames it drew besides the PNG files: a video encoded by
// ffmpeg (run as a subprocess) and a contact sheet (a labelled grid of frames).

#include <asyncfem/image/image.hpp>
#include <filesystem>
#include <string>
#include <vector>

namespace asyncfem::media {

/// The executable `name` found on PATH (empty when there is none).
std::filesystem::path findOnPath(const std::string& name);

/// ffmpeg on PATH; throws asyncfem::Error saying how to install it when there is none.
std::filesystem::path requireFfmpeg();

/// Encodes the PNG files `frames` (in this order, all of one size) into `output` at `fps`
/// frames per second with `ffmpeg`; the container follows output's extension (.mp4, .mov,
/// .m4v and .mkv get H.264 in yuv420p, widths and heights padded to even numbers). ffmpeg
/// writes a temporary file next to output, renamed to output only when ffmpeg succeeded;
/// on failure it is removed, output is left as it was and asyncfem::Error carries the end
/// of ffmpeg's messages.
void encodeVideo(const std::filesystem::path& ffmpeg, const std::vector<std::filesystem::path>& frames,
                 const std::filesystem::path& output, double fps);

/// Height of the label bar under each tile of a contact sheet of tiles tileHeight high.
int contactSheetLabelHeight(int tileHeight);

/// The tiles (all of one size) in a grid `columns` wide, left to right and top to bottom,
/// each over a white bar with its label in dark grey, centred: an image of
/// min(columns, n) tile widths by ceil(n / columns) (tile height + label bar) heights.
Image contactSheet(const std::vector<Image>& tiles, const std::vector<std::string>& labels, int columns);

}  // namespace asyncfem::media
