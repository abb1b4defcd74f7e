// SPDX-License-Identifier: BSD-3-Clause
#include "frameMedia.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/image/text.hpp>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <system_error>

extern char** environ;

namespace asyncfem::media {

namespace fs = std::filesystem;

fs::path findOnPath(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::istringstream folders(path != nullptr ? path : "");
  std::string folder;
  while (std::getline(folders, folder, ':')) {
    const fs::path candidate = fs::path(folder.empty() ? "." : folder) / name;
    if (::access(candidate.c_str(), X_OK) == 0 && !fs::is_directory(candidate)) {
      return candidate;
    }
  }
  return {};
}

fs::path requireFfmpeg() {
  fs::path ffmpeg = findOnPath("ffmpeg");
  if (ffmpeg.empty()) {
    throw Error(
        "--video needs ffmpeg, which is not on PATH: install it (Debian: sudo apt-get install ffmpeg, or "
        "scripts/install-deps.sh), or leave --video out and encode the PNG frames yourself");
  }
  return ffmpeg;
}

namespace {

/// Removes a path (file or folder) when it goes out of scope, unless released.
class RemoveOnExit {
 public:
  explicit RemoveOnExit(fs::path path) : path_(std::move(path)) {}
  RemoveOnExit(const RemoveOnExit&) = delete;
  RemoveOnExit& operator=(const RemoveOnExit&) = delete;
  ~RemoveOnExit() {
    std::error_code ignored;
    if (!path_.empty()) fs::remove_all(path_, ignored);
  }
  void release() { path_.clear(); }

 private:
  fs::path path_;
};

std::string lowerExtension(const fs::path& path) {
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension;
}

/// The last lines of a log file (what ffmpeg said before failing).
std::string tailOf(const fs::path& log, std::size_t maxLines = 6) {
  std::ifstream in(log);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) {
    if (!line.empty()) lines.push_back(line);
  }
  std::string text;
  for (std::size_t i = lines.size() > maxLines ? lines.size() - maxLines : 0; i < lines.size(); ++i) {
    text += "\n  " + lines[i];
  }
  return text;
}

/// Runs argv[0] with stdout and stderr to log; its exit status (128 + signal when killed).
int runLogged(const std::vector<std::string>& arguments, const fs::path& log) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  std::vector<char*> argv;
  for (const std::string& argument : arguments) argv.push_back(const_cast<char*>(argument.c_str()));
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int spawned = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) {
    throw Error("cannot run " + arguments[0] + ": " + std::system_category().message(spawned));
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) throw Error("waiting for " + arguments[0] + " failed");
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
}

}  // namespace

void encodeVideo(const fs::path& ffmpeg, const std::vector<fs::path>& frames, const fs::path& output, double fps) {
  if (frames.empty()) throw Error("--video: no frames to encode");
  const std::string extension = lowerExtension(output);
  if (extension.empty()) {
    throw Error("--video " + output.string() + ": give a file name with an extension (.mp4, .mkv, .webm, .gif)");
  }
  const fs::path folder = fs::absolute(output).parent_path();
  fs::create_directories(folder);
  const std::string tag = ".frameRenderer-" + std::to_string(::getpid());
  // Numbered links to the frames: ffmpeg's image sequence wants consecutive numbers, the
  // frames keep their own indices (frame_00000.png, frame_00005.png, ...).
  const fs::path sequence = folder / (tag + "-frames");
  fs::remove_all(sequence);
  fs::create_directories(sequence);
  const RemoveOnExit removeSequence(sequence);
  for (std::size_t i = 0; i < frames.size(); ++i) {
    char name[32];
    std::snprintf(name, sizeof(name), "%06zu.png", i);
    fs::create_symlink(fs::absolute(frames[i]), sequence / name);
  }
  const fs::path partial = folder / (output.stem().string() + tag + ".partial" + output.extension().string());
  RemoveOnExit removePartial(partial);
  char rate[32];
  std::snprintf(rate, sizeof(rate), "%.9g", fps);
  std::vector<std::string> arguments{ffmpeg.string(),
                                     "-nostdin",
                                     "-hide_banner",
                                     "-loglevel",
                                     "error",
                                     "-y",
                                     "-framerate",
                                     rate,
                                     "-i",
                                     (sequence / "%06d.png").string()};
  if (extension == ".mp4" || extension == ".m4v" || extension == ".mov" || extension == ".mkv") {
    for (const char* a : {"-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-c:v", "libx264", "-pix_fmt", "yuv420p"}) {
      arguments.emplace_back(a);
    }
    if (extension != ".mkv") {
      arguments.emplace_back("-movflags");
      arguments.emplace_back("+faststart");
    }
  }
  arguments.push_back(partial.string());
  const fs::path log = sequence / "ffmpeg.log";
  const int status = runLogged(arguments, log);
  if (status != 0 || !fs::exists(partial) || fs::file_size(partial) == 0) {
    throw Error("ffmpeg failed to encode " + output.string() + " (exit status " + std::to_string(status) +
                "); no video was written. ffmpeg said:" + tailOf(log));
  }
  fs::rename(partial, output);
  removePartial.release();
}

int contactSheetLabelHeight(int tileHeight) { return std::max(14, tileHeight / 10); }

Image contactSheet(const std::vector<Image>& tiles, const std::vector<std::string>& labels, int columns) {
  if (tiles.empty()) throw Error("contact sheet: no frames");
  if (labels.size() != tiles.size()) throw Error("contact sheet: one label per frame expected");
  const int width = tiles.front().width;
  const int height = tiles.front().height;
  for (const Image& tile : tiles) {
    if (tile.width != width || tile.height != height) throw Error("contact sheet: frames of different sizes");
  }
  const int count = static_cast<int>(tiles.size());
  columns = std::clamp(columns, 1, count);
  const int rows = (count + columns - 1) / columns;
  const int bar = contactSheetLabelHeight(height);
  const int cellHeight = height + bar;
  Image sheet(columns * width, rows * cellHeight, Rgb8{255, 255, 255});
  const Rgb8 ink{40, 40, 40};
  for (int i = 0; i < count; ++i) {
    const int x = (i % columns) * width;
    const int y = (i / columns) * cellHeight;
    sheet.paste(tiles[static_cast<std::size_t>(i)], x, y);
    const std::string& label = labels[static_cast<std::size_t>(i)];
    int scale = std::max(1, (bar - 4) / glyphHeight);
    while (scale > 1 && textWidth(label, scale) > width - 4) --scale;
    drawText(sheet, x + std::max(2, (width - textWidth(label, scale)) / 2),
             y + height + (bar - glyphHeight * scale) / 2, label, scale, ink);
    // A thin rule between cells, so that tiles of one background stay apart.
    if (i % columns != 0) sheet.fillRectangle(x, y, x + 1, y + cellHeight, Rgb8{200, 200, 200});
    if (i >= columns) sheet.fillRectangle(x, y, x + width, y + 1, Rgb8{200, 200, 200});
  }
  return sheet;
}

}  // namespace asyncfem::media
