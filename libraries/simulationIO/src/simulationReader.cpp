// SPDX-License-Identifier: BSD-3-Clause
#include <sys/types.h>

#include <asyncfem/core/error.hpp>
#include <asyncfem/simulationIO/crc32.hpp>
#include <asyncfem/simulationIO/simulationFile.hpp>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <string>

#include "detail/byteOrder.hpp"

namespace asyncfem {

void SimulationReader::FileCloser::operator()(std::FILE* file) const { std::fclose(file); }

namespace {

std::string hex32(std::uint32_t value) {
  static constexpr char digits[] = "0123456789abcdef";
  std::string text = "0x00000000";
  for (int i = 0; i < 8; ++i) {
    text[static_cast<std::size_t>(9 - i)] = digits[(value >> (4 * i)) & 0xFU];
  }
  return text;
}

/// Format version and header size of a file.
struct HeaderLayout {
  std::uint32_t version = 0;
  std::uint32_t headerBytes = 0;
};

/// Checks the fixed part of a header (got bytes read into bytes): the magic, its size,
/// the format version, the header size and the checksum.
HeaderLayout checkHeaderFrame(const std::string& name, const unsigned char* bytes, std::size_t got) {
  if (got < sizeof(detail::simulationMagic) ||
      std::memcmp(bytes, detail::simulationMagic, sizeof(detail::simulationMagic)) != 0) {
    if (got < sizeof(detail::simulationMagic)) {
      throw ParseError(
          name, 0,
          "truncated header: " + std::to_string(got) + " bytes, expected " + std::to_string(simulationHeaderBytes));
    }
    throw ParseError(name, 0, "not an AsyncFEM simulation file (bad magic)");
  }
  if (got < simulationHeaderBytes) {
    throw ParseError(
        name, 0,
        "truncated header: " + std::to_string(got) + " bytes, expected " + std::to_string(simulationHeaderBytes));
  }
  const std::uint32_t version = detail::getU32(bytes + detail::offsetVersion);
  if (version != 1 && version != 2) {
    throw ParseError(name, 0,
                     "unsupported format version " + std::to_string(version) + " (this build reads 1 to " +
                         std::to_string(simulationFileVersion) + ")");
  }
  const std::uint32_t headerBytes = detail::getU32(bytes + detail::offsetHeaderBytes);
  const std::uint32_t maxHeaderBytes = simulationHeaderBytes + 16 + maxSimulationScenePath + 8;
  if (version == 1
          ? headerBytes != simulationHeaderBytes
          : (headerBytes < simulationHeaderBytes + 24 || headerBytes > maxHeaderBytes || headerBytes % 8 != 0)) {
    throw ParseError(
        name, 0,
        "header size " + std::to_string(headerBytes) + " is not valid for format version " + std::to_string(version));
  }
  const std::uint32_t storedCrc = detail::getU32(bytes + detail::offsetHeaderCrc);
  const std::uint32_t actualCrc = crc32(bytes, detail::offsetHeaderCrc);
  if (storedCrc != actualCrc) {
    throw ParseError(name, 0,
                     "header checksum mismatch (stored " + hex32(storedCrc) + ", computed " + hex32(actualCrc) +
                         "): the header is corrupted");
  }
  return {version, headerBytes};
}

/// Reads the vertex count, frame interval, timestep and flags of a checked header into
/// header, and checks them and the record size. Sizes are checked before anything is
/// allocated from them.
void readHeaderFields(const std::string& name, const unsigned char* bytes, SimulationFileHeader& header) {
  const std::uint64_t numVertices = detail::getU64(bytes + detail::offsetNumVertices);
  if (numVertices == 0 || numVertices > static_cast<std::uint64_t>(maxSimulationFileVertices)) {
    throw ParseError(name, 0,
                     "header claims " + std::to_string(numVertices) + " vertices (expected 1 to " +
                         std::to_string(maxSimulationFileVertices) + ")");
  }
  header.numVertices = static_cast<std::int64_t>(numVertices);
  header.frameInterval = detail::getF64(bytes + detail::offsetFrameInterval);
  header.timestep = detail::getF64(bytes + detail::offsetTimestep);
  if (!std::isfinite(header.frameInterval) || header.frameInterval < 0.0 || !std::isfinite(header.timestep) ||
      header.timestep < 0.0) {
    throw ParseError(name, 0, "header has a non-finite or negative frame interval or timestep");
  }
  const std::uint64_t flags = detail::getU64(bytes + detail::offsetFlags);
  if ((flags & ~detail::knownFlags) != 0) {
    throw ParseError(name, 0, "header has unknown flags " + std::to_string(flags));
  }
  header.hasVelocities = (flags & detail::flagVelocities) != 0;
  header.hasRegionRatios = (flags & detail::flagRegionRatios) != 0;
  header.hasContactForces = (flags & detail::flagContactForces) != 0;
  const std::uint64_t recordBytes = detail::getU64(bytes + detail::offsetRecordBytes);
  if (recordBytes != static_cast<std::uint64_t>(header.recordBytes())) {
    throw ParseError(name, 0,
                     "header record size " + std::to_string(recordBytes) + " disagrees with " +
                         std::to_string(numVertices) + " vertices" +
                         (header.hasRegionRatios ? " with region ratios" : "") + " (expected " +
                         std::to_string(header.recordBytes()) + ")");
  }
}

/// Checks the checksum and the frame index of the record of frame k (recordBytes at in).
void checkRecord(const std::string& name, std::int64_t k, const unsigned char* in, std::size_t recordBytes) {
  const std::size_t crcOffset = recordBytes - detail::recordSuffixBytes;
  const std::uint32_t storedCrc = detail::getU32(in + crcOffset);
  const std::uint32_t actualCrc = crc32(in, crcOffset);
  if (storedCrc != actualCrc) {
    throw ParseError(name, 0,
                     "frame " + std::to_string(k) + ": checksum mismatch (stored " + hex32(storedCrc) + ", computed " +
                         hex32(actualCrc) + "): the record is corrupted");
  }
  const auto index = static_cast<std::int64_t>(detail::getU64(in));
  if (index != k) {
    throw ParseError(name, 0, "frame " + std::to_string(k) + ": record says it is frame " + std::to_string(index));
  }
}

/// Reads the n region ratios of frame k at in into out; each must be at least 1, and the
/// padding after them zero.
void readRatios(const std::string& name, std::int64_t k, const unsigned char* in, std::int64_t numVertices,
                std::vector<std::uint16_t>& out) {
  out.resize(static_cast<std::size_t>(numVertices));
  for (std::size_t v = 0; v < out.size(); ++v) {
    out[v] = detail::getU16(in + (2 * v));
    if (out[v] == 0) {
      throw ParseError(name, 0,
                       "frame " + std::to_string(k) + ": vertex " + std::to_string(v) +
                           " has region ratio 0 (step ratios are 1 or more)");
    }
  }
  for (auto b = static_cast<std::size_t>(2 * numVertices);
       b < static_cast<std::size_t>(detail::regionRatioBytes(numVertices)); ++b) {
    if (in[b] != 0) {
      throw ParseError(name, 0, "frame " + std::to_string(k) + ": the padding after the region ratios is not zero");
    }
  }
}

}  // namespace

SimulationReader::SimulationReader(const std::filesystem::path& path) : path_(path) {
  const std::string name = path.string();
  file_.reset(std::fopen(name.c_str(), "rb"));
  if (!file_) {
    throw Error(name + ": cannot open: " + std::strerror(errno));
  }
  unsigned char bytes[simulationHeaderBytes] = {};
  const std::size_t got = std::fread(bytes, 1, sizeof(bytes), file_.get());
  const HeaderLayout layout = checkHeaderFrame(name, bytes, got);
  readHeaderFields(name, bytes, header_);
  if (layout.version == 2) readSceneBlock(layout.headerBytes);
  refresh();
}

void SimulationReader::readSceneBlock(std::uint32_t headerBytes) {
  const std::string name = path_.string();
  std::vector<unsigned char> block(headerBytes - simulationHeaderBytes, 0);
  if (std::fread(block.data(), 1, block.size(), file_.get()) != block.size()) {
    throw ParseError(name, 0, "truncated scene block in the header (" + std::to_string(headerBytes) + " bytes)");
  }
  const std::size_t crcAt = block.size() - 8;
  if (detail::getU32(block.data() + crcAt) != crc32(block.data(), crcAt)) {
    throw ParseError(name, 0, "scene block checksum mismatch: the header is corrupted");
  }
  const std::uint32_t length = detail::getU32(block.data() + 4);
  if (length == 0 || length > maxSimulationScenePath || 8 + ((length + 7) / 8 * 8) != crcAt) {
    throw ParseError(name, 0, "scene block has a path length " + std::to_string(length) + " that does not fit it");
  }
  header_.sceneFingerprint = detail::getU32(block.data());
  header_.scenePath.assign(reinterpret_cast<const char*>(block.data() + 8), length);
}

SimulationReader::~SimulationReader() = default;

void SimulationReader::refresh() {
  if (::fseeko(file_.get(), 0, SEEK_END) != 0) {
    throw Error(path_.string() + ": cannot seek: " + std::strerror(errno));
  }
  const auto size = static_cast<std::int64_t>(::ftello(file_.get()));
  if (size < header_.headerBytes()) {
    throw ParseError(path_.string(), 0, "the file shrank below its header while being read");
  }
  const std::int64_t payload = size - header_.headerBytes();
  numFrames_ = payload / header_.recordBytes();
  trailingBytes_ = payload % header_.recordBytes();
}

SimulationFrame SimulationReader::readFrame(std::int64_t k) {
  SimulationFrame frame;
  readFrame(k, frame);
  return frame;
}

void SimulationReader::readFrame(std::int64_t k, SimulationFrame& out) {
  const std::string where = path_.string() + ": frame " + std::to_string(k);
  if (k < 0 || k >= numFrames_) {
    throw Error(where + ": out of range (the file has " + std::to_string(numFrames_) + " complete frames)");
  }
  const auto recordBytes = static_cast<std::size_t>(header_.recordBytes());
  buffer_.resize(recordBytes);
  const std::int64_t offset = header_.headerBytes() + (k * header_.recordBytes());
  if (::fseeko(file_.get(), static_cast<off_t>(offset), SEEK_SET) != 0 ||
      std::fread(buffer_.data(), 1, recordBytes, file_.get()) != recordBytes) {
    throw ParseError(path_.string(), 0, "frame " + std::to_string(k) + ": cannot read the record");
  }
  const unsigned char* in = buffer_.data();
  checkRecord(path_.string(), k, in, recordBytes);
  out.index = k;
  out.time = detail::getF64(in + 8);
  const auto size = static_cast<Eigen::Index>(3 * header_.numVertices);
  std::size_t position = detail::recordPrefixBytes;
  // The 3n doubles of one array where the record carries it, in the record's order.
  const auto readArray = [&](bool present, Eigen::VectorXd& array) {
    array.resize(present ? size : 0);
    for (Eigen::Index i = 0; i < array.size(); ++i, position += 8) array[i] = detail::getF64(in + position);
  };
  readArray(true, out.displacement);
  readArray(header_.hasVelocities, out.velocity);
  readArray(header_.hasContactForces, out.contactForce);
  if (header_.hasRegionRatios) {
    readRatios(path_.string(), k, in + position, header_.numVertices, out.regionRatios);
  } else {
    out.regionRatios.clear();
  }
}

void SimulationReader::verifyAll() {
  SimulationFrame frame;
  for (std::int64_t k = 0; k < numFrames_; ++k) {
    readFrame(k, frame);
  }
}

RecordScan SimulationReader::scanRecords() {
  RecordScan scan;
  SimulationFrame frame;
  for (std::int64_t k = 0; k < numFrames_; ++k) {
    try {
      readFrame(k, frame);
    } catch (const ParseError& error) {
      scan.badFrame = k;
      scan.badMessage = error.what();
      break;
    }
    if (k == 0) scan.firstTime = frame.time;
    scan.lastTime = frame.time;
    scan.goodFrames = k + 1;
  }
  return scan;
}

}  // namespace asyncfem
