// SPDX-License-Identifier: BSD-3-Clause
#include <fcntl.h>
#include <unistd.h>

#include <asyncfem/core/error.hpp>
#include <asyncfem/simulationIO/checkpoint.hpp>
#include <asyncfem/simulationIO/crc32.hpp>
#include <asyncfem/simulationIO/simulationFile.hpp>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "detail/byteOrder.hpp"
#include "detail/systemMessage.hpp"

namespace asyncfem {

namespace {

constexpr char checkpointMagic[8] = {'A', 'F', 'E', 'M', 'C', 'K', 'P', '\0'};
constexpr std::size_t headerBytes = 64;
constexpr std::size_t offsetVersion = 8;
constexpr std::size_t offsetHeaderBytes = 12;
constexpr std::size_t offsetFrames = 16;
constexpr std::size_t offsetTime = 24;
constexpr std::size_t offsetNumDofs = 32;
constexpr std::size_t offsetInternal = 40;
constexpr std::size_t offsetFingerprint = 48;
constexpr std::size_t offsetNameLength = 52;
constexpr std::size_t offsetMonitor = 56;  // reserved (0) in version 1
constexpr std::uint64_t maxMonitorState = 1024;
constexpr std::size_t offsetHeaderCrc = 60;
constexpr std::size_t maxNameLength = 64;
constexpr std::size_t suffixBytes = 8;

std::size_t paddedName(std::size_t length) { return (length + 7) / 8 * 8; }

using detail::systemMessage;

// Owns a POSIX file descriptor.
class Descriptor {
 public:
  explicit Descriptor(int fd) : fd_(fd) {}
  ~Descriptor() {
    if (fd_ >= 0) ::close(fd_);
  }
  Descriptor(const Descriptor&) = delete;
  Descriptor& operator=(const Descriptor&) = delete;
  int get() const { return fd_; }
  int release() {
    const int fd = fd_;
    fd_ = -1;
    return fd;
  }

 private:
  int fd_;
};

/// Refuses a checkpoint that cannot be stored: a bad integrator name, state vectors of
/// different sizes, a negative frame count or non-finite values.
void checkStorable(const std::string& name, const SimulationCheckpoint& checkpoint) {
  const std::size_t nameLength = checkpoint.integrator.size();
  if (nameLength == 0 || nameLength > maxNameLength) {
    throw Error(name + ": the integrator name must have 1 to 64 characters");
  }
  if (checkpoint.displacement.size() != checkpoint.velocity.size()) {
    throw Error(name + ": displacement and velocity sizes differ (" + std::to_string(checkpoint.displacement.size()) +
                " and " + std::to_string(checkpoint.velocity.size()) + ")");
  }
  if (checkpoint.frames < 0 || !std::isfinite(checkpoint.time) || !checkpoint.displacement.allFinite() ||
      !checkpoint.velocity.allFinite() || !checkpoint.internalState.allFinite() ||
      !checkpoint.monitorState.allFinite() ||
      static_cast<std::uint64_t>(checkpoint.monitorState.size()) > maxMonitorState) {
    throw Error(name + ": refusing to store a negative frame count, non-finite values or over 1024 monitor values");
  }
}

/// The bytes of a checkpoint file: header, integrator name, the four vectors, checksum.
std::vector<unsigned char> encodeCheckpoint(const SimulationCheckpoint& checkpoint) {
  const std::size_t nameLength = checkpoint.integrator.size();
  const auto numDofs = static_cast<std::size_t>(checkpoint.displacement.size());
  const auto internal = static_cast<std::size_t>(checkpoint.internalState.size());
  const auto monitor = static_cast<std::size_t>(checkpoint.monitorState.size());
  const std::size_t total =
      headerBytes + paddedName(nameLength) + (8 * (2 * numDofs + internal + monitor)) + suffixBytes;
  std::vector<unsigned char> bytes(total, 0);
  unsigned char* out = bytes.data();
  std::memcpy(out, checkpointMagic, sizeof(checkpointMagic));
  detail::putU32(out + offsetVersion, checkpointFileVersion);
  detail::putU32(out + offsetHeaderBytes, static_cast<std::uint32_t>(headerBytes));
  detail::putU64(out + offsetFrames, static_cast<std::uint64_t>(checkpoint.frames));
  detail::putF64(out + offsetTime, checkpoint.time);
  detail::putU64(out + offsetNumDofs, numDofs);
  detail::putU64(out + offsetInternal, internal);
  detail::putU32(out + offsetFingerprint, checkpoint.fingerprint);
  detail::putU32(out + offsetNameLength, static_cast<std::uint32_t>(nameLength));
  detail::putU32(out + offsetMonitor, static_cast<std::uint32_t>(monitor));
  detail::putU32(out + offsetHeaderCrc, crc32(out, offsetHeaderCrc));
  std::memcpy(out + headerBytes, checkpoint.integrator.data(), nameLength);
  std::size_t offset = headerBytes + paddedName(nameLength);
  for (const Eigen::VectorXd* values :
       {&checkpoint.displacement, &checkpoint.velocity, &checkpoint.internalState, &checkpoint.monitorState}) {
    for (Eigen::Index i = 0; i < values->size(); ++i, offset += 8) detail::putF64(out + offset, (*values)[i]);
  }
  detail::putU32(out + offset, crc32(out, offset));
  return bytes;
}

/// Writes bytes to PATH.tmp (fsync'ed when sync) and renames it to path, so that path
/// holds either the old or the new contents.
void replaceFile(const std::filesystem::path& path, const std::vector<unsigned char>& bytes, bool sync) {
  const std::string name = path.string();
  std::filesystem::path temporary = path;
  temporary += ".tmp";
  const std::string temporaryName = temporary.string();
  Descriptor fd(::open(temporaryName.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644));
  if (fd.get() < 0) throw Error(temporaryName + ": cannot create: " + systemMessage());
  // On failure the partial temporary file goes; the previous checkpoint stays as it was.
  const auto fail = [&](const std::string& message) {
    const std::string cause = systemMessage();
    if (fd.get() >= 0) ::close(fd.release());
    ::unlink(temporaryName.c_str());
    throw Error(message + ": " + cause + "; the previous checkpoint " + name + " is unchanged");
  };
  std::size_t written = 0;
  while (written < bytes.size()) {
    const ssize_t n = ::write(fd.get(), bytes.data() + written, bytes.size() - written);
    if (n < 0) {
      if (errno == EINTR) continue;
      fail(temporaryName + ": write failed");
    }
    written += static_cast<std::size_t>(n);
  }
  if (sync && ::fsync(fd.get()) != 0) fail(temporaryName + ": fsync failed");
  if (::close(fd.release()) != 0) fail(temporaryName + ": cannot close");
  if (std::rename(temporaryName.c_str(), name.c_str()) != 0) fail(name + ": cannot rename " + temporaryName + " to it");
}

/// Checks a checkpoint's fixed header: size, magic, version, header size, checksum.
void checkCheckpointHeader(const unsigned char* data, std::size_t size, const std::string& name) {
  if (size < headerBytes) {
    throw ParseError(name, 0, "truncated checkpoint: " + std::to_string(size) + " bytes, expected at least 64");
  }
  if (std::memcmp(data, checkpointMagic, sizeof(checkpointMagic)) != 0) {
    throw ParseError(name, 0, "not an AsyncFEM checkpoint (bad magic)");
  }
  const std::uint32_t version = detail::getU32(data + offsetVersion);
  // Version 1: no monitor state; 1 and 2: no kept-factor state (the same layout as 3).
  if (version < 1 || version > checkpointFileVersion) {
    throw ParseError(name, 0,
                     "unsupported checkpoint version " + std::to_string(version) + " (this build reads versions 1 to " +
                         std::to_string(checkpointFileVersion) + "; it was written by a newer AsyncFEM)");
  }
  if (detail::getU32(data + offsetHeaderBytes) != headerBytes) {
    throw ParseError(name, 0, "checkpoint header size is not 64");
  }
  if (detail::getU32(data + offsetHeaderCrc) != crc32(data, offsetHeaderCrc)) {
    throw ParseError(name, 0, "checkpoint header checksum mismatch: the file is corrupted");
  }
}

/// The counts a checked header gives.
struct CheckpointCounts {
  std::uint64_t frames = 0;
  std::uint64_t numDofs = 0;
  std::uint64_t internal = 0;
  std::uint64_t monitor = 0;
  std::uint32_t nameLength = 0;
};

/// Reads the counts of a checked header and checks them against each other and the file
/// size (before anything is allocated from them), then the whole file's checksum.
CheckpointCounts checkedCounts(const unsigned char* data, std::size_t size, const std::string& name) {
  CheckpointCounts counts;
  counts.frames = detail::getU64(data + offsetFrames);
  counts.numDofs = detail::getU64(data + offsetNumDofs);
  counts.internal = detail::getU64(data + offsetInternal);
  counts.nameLength = detail::getU32(data + offsetNameLength);
  counts.monitor = detail::getU32(data + offsetMonitor);
  if (counts.frames > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max())) {
    throw ParseError(name, 0, "checkpoint claims a negative frame count");
  }
  if (counts.nameLength == 0 || counts.nameLength > maxNameLength) {
    throw ParseError(
        name, 0,
        "checkpoint integrator name has " + std::to_string(counts.nameLength) + " characters (expected 1 to 64)");
  }
  const std::uint64_t limit = 3 * static_cast<std::uint64_t>(maxSimulationFileVertices);
  // The internal state: at most a few vectors of the state's size (backward Euler's kept
  // factor: dv, two displacements and the contact blocks of every vertex).
  if (counts.numDofs > limit || counts.numDofs % 3 != 0 || counts.internal > 16 * limit ||
      counts.monitor > maxMonitorState) {
    throw ParseError(name, 0,
                     "checkpoint claims " + std::to_string(counts.numDofs) + " state entries, " +
                         std::to_string(counts.internal) + " internal ones and " + std::to_string(counts.monitor) +
                         " monitor values");
  }
  const std::uint64_t expected = headerBytes + paddedName(counts.nameLength) +
                                 (8 * ((2 * counts.numDofs) + counts.internal + counts.monitor)) + suffixBytes;
  if (expected != size) {
    throw ParseError(name, 0,
                     "checkpoint is " + std::to_string(size) + " bytes, its header implies " +
                         std::to_string(expected) + ": the file is truncated or corrupted");
  }
  const std::size_t crcOffset = size - suffixBytes;
  if (detail::getU32(data + crcOffset) != crc32(data, crcOffset)) {
    throw ParseError(name, 0, "checkpoint checksum mismatch: the file is corrupted");
  }
  return counts;
}

}  // namespace

std::filesystem::path checkpointPathFor(const std::filesystem::path& outputPath) {
  std::filesystem::path path = outputPath;
  path += ".checkpoint";
  return path;
}

void writeCheckpoint(const std::filesystem::path& path, const SimulationCheckpoint& checkpoint, bool sync) {
  checkStorable(path.string(), checkpoint);
  replaceFile(path, encodeCheckpoint(checkpoint), sync);
}

SimulationCheckpoint parseCheckpoint(const unsigned char* data, std::size_t size, const std::string& name) {
  checkCheckpointHeader(data, size, name);
  const CheckpointCounts counts = checkedCounts(data, size, name);
  SimulationCheckpoint checkpoint;
  checkpoint.frames = static_cast<std::int64_t>(counts.frames);
  checkpoint.time = detail::getF64(data + offsetTime);
  checkpoint.fingerprint = detail::getU32(data + offsetFingerprint);
  checkpoint.integrator.assign(reinterpret_cast<const char*>(data + headerBytes), counts.nameLength);
  std::size_t offset = headerBytes + paddedName(counts.nameLength);
  const auto read = [&](Eigen::VectorXd& values, std::uint64_t count) {
    values.resize(static_cast<Eigen::Index>(count));
    for (Eigen::Index i = 0; i < values.size(); ++i, offset += 8) values[i] = detail::getF64(data + offset);
  };
  read(checkpoint.displacement, counts.numDofs);
  read(checkpoint.velocity, counts.numDofs);
  read(checkpoint.internalState, counts.internal);
  read(checkpoint.monitorState, counts.monitor);
  if (!std::isfinite(checkpoint.time) || !checkpoint.displacement.allFinite() || !checkpoint.velocity.allFinite() ||
      !checkpoint.internalState.allFinite() || !checkpoint.monitorState.allFinite()) {
    throw ParseError(name, 0, "checkpoint holds non-finite values");
  }
  return checkpoint;
}

SimulationCheckpoint readCheckpoint(const std::filesystem::path& path) {
  const std::string name = path.string();
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(name + ": cannot open: " + systemMessage());
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (size < 0) throw Error(name + ": cannot read its size");
  // The largest valid checkpoint is bounded by the size limits checked in parseCheckpoint;
  // reading the file whole is fine because its size is what it is on disk.
  std::vector<unsigned char> bytes(static_cast<std::size_t>(size));
  in.seekg(0, std::ios::beg);
  if (size > 0 && !in.read(reinterpret_cast<char*>(bytes.data()), size)) {
    throw Error(name + ": read failed: " + systemMessage());
  }
  return parseCheckpoint(bytes.data(), bytes.size(), name);
}

}  // namespace asyncfem
