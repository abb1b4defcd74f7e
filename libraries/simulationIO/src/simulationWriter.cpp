// SPDX-License-Identifier: BSD-3-Clause
#include <fcntl.h>
#include <stdio_ext.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/simulationIO/crc32.hpp>
#include <asyncfem/simulationIO/simulationFile.hpp>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "detail/byteOrder.hpp"
#include "detail/systemMessage.hpp"

namespace asyncfem {

std::int64_t SimulationFileHeader::headerBytes() const {
  if (scenePath.empty()) return simulationHeaderBytes;
  const auto padded = static_cast<std::int64_t>((scenePath.size() + 7) / 8 * 8);
  return simulationHeaderBytes + 8 + padded + 8;
}

std::int64_t SimulationFileHeader::recordBytes() const {
  const std::int64_t arrays = 1 + (hasVelocities ? 1 : 0) + (hasContactForces ? 1 : 0);
  return static_cast<std::int64_t>(detail::recordPrefixBytes + detail::recordSuffixBytes) +
         (arrays * 3 * numVertices * static_cast<std::int64_t>(sizeof(double))) +
         (hasRegionRatios ? detail::regionRatioBytes(numVertices) : 0);
}

void SimulationWriter::FileCloser::operator()(std::FILE* file) const { std::fclose(file); }

namespace {

// Fault-injection seam for the storage-fault tests (docs/robustness.md, "Faults, counted"),
// off unless the environment sets it: ASYNCFEM_TEST_STOP_BEFORE_FRAME=K stops the process
// (SIGSTOP) before frame K is checked and written, so that a test can delete, truncate or
// protect the file at a known frame and then continue the process (SIGCONT).
void stopBeforeFrameIfAsked(std::int64_t frame) {
  const char* value = std::getenv("ASYNCFEM_TEST_STOP_BEFORE_FRAME");
  if (value != nullptr && *value != '\0' && std::strtoll(value, nullptr, 10) == frame) std::raise(SIGSTOP);
}

using detail::systemMessage;

std::string framesText(std::int64_t frames) {
  return std::to_string(frames) + (frames == 1 ? " complete frame" : " complete frames");
}

// Writes the first `bytes` bytes of the open file `from` to a new file at `path` (which
// must not exist). Returns false, with errno set, when it cannot.
bool copyBack(int from, const std::filesystem::path& path, std::int64_t bytes) {
  const int to = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (to < 0) return false;
  std::vector<char> block(1 << 16);
  bool ok = true;
  for (std::int64_t offset = 0; ok && offset < bytes;) {
    const auto want = static_cast<std::size_t>(std::min<std::int64_t>(bytes - offset, std::ssize(block)));
    const ssize_t got = ::pread(from, block.data(), want, static_cast<off_t>(offset));
    ok = got > 0 && ::write(to, block.data(), static_cast<std::size_t>(got)) == got;
    offset += got > 0 ? got : 0;
  }
  const int saved = errno;
  ok = ::close(to) == 0 && ok;
  if (!ok) errno = saved;
  return ok;
}

// n ratios, each one a u16 of at least 1.
void checkRatios(const std::string& where, const std::vector<int>& ratios, std::int64_t numVertices) {
  if (std::ssize(ratios) != numVertices) {
    throw Error(where + ": expected " + std::to_string(numVertices) + " region ratios, got " +
                std::to_string(ratios.size()));
  }
  for (std::size_t v = 0; v < ratios.size(); ++v) {
    if (ratios[v] < 1 || ratios[v] > maxSimulationRegionRatio) {
      throw Error(where + ": vertex " + std::to_string(v) + ": step ratio " + std::to_string(ratios[v]) +
                  " cannot be stored (a record holds ratios from 1 to " + std::to_string(maxSimulationRegionRatio) +
                  ")");
    }
  }
}

void checkHeader(const std::string& name, const SimulationFileHeader& header) {
  if (header.numVertices <= 0 || header.numVertices > maxSimulationFileVertices) {
    throw Error(name + ": cannot write a simulation file with " + std::to_string(header.numVertices) + " vertices");
  }
  if (!std::isfinite(header.frameInterval) || header.frameInterval < 0.0 || !std::isfinite(header.timestep) ||
      header.timestep < 0.0) {
    throw Error(name + ": frame interval and timestep must be finite and >= 0");
  }
  if (header.scenePath.size() > maxSimulationScenePath) {
    throw Error(name + ": the scene path is longer than " + std::to_string(maxSimulationScenePath) + " bytes");
  }
}

std::vector<unsigned char> encodeHeader(const SimulationFileHeader& header) {
  std::vector<unsigned char> block(static_cast<std::size_t>(header.headerBytes()), 0);
  unsigned char* bytes = block.data();
  std::memcpy(bytes, detail::simulationMagic, sizeof(detail::simulationMagic));
  detail::putU32(bytes + detail::offsetVersion, header.scenePath.empty() ? 1U : 2U);
  detail::putU32(bytes + detail::offsetHeaderBytes, static_cast<std::uint32_t>(header.headerBytes()));
  detail::putU64(bytes + detail::offsetNumVertices, static_cast<std::uint64_t>(header.numVertices));
  detail::putF64(bytes + detail::offsetFrameInterval, header.frameInterval);
  detail::putF64(bytes + detail::offsetTimestep, header.timestep);
  detail::putU64(bytes + detail::offsetFlags, detail::headerFlags(header));
  detail::putU64(bytes + detail::offsetRecordBytes, static_cast<std::uint64_t>(header.recordBytes()));
  detail::putU32(bytes + detail::offsetHeaderCrc, crc32(bytes, detail::offsetHeaderCrc));
  if (!header.scenePath.empty()) {
    unsigned char* scene = bytes + simulationHeaderBytes;
    detail::putU32(scene, header.sceneFingerprint);
    detail::putU32(scene + 4, static_cast<std::uint32_t>(header.scenePath.size()));
    std::memcpy(scene + 8, header.scenePath.data(), header.scenePath.size());
    const std::size_t crcAt = block.size() - 8;
    detail::putU32(bytes + crcAt, crc32(scene, crcAt - simulationHeaderBytes));
  }
  return block;
}

// A file continued by a run that would write other records: the flag that differs, named.
void checkSameFlags(const std::string& name, const unsigned char* stored, const SimulationFileHeader& header) {
  if (std::memcmp(stored, detail::simulationMagic, sizeof(detail::simulationMagic)) != 0) return;
  const std::uint64_t there = detail::getU64(stored + detail::offsetFlags);
  const std::uint64_t here = detail::headerFlags(header);
  const auto differs = [&](std::uint64_t flag, const char* what, const char* key) {
    if ((there & flag) == (here & flag)) return;
    throw Error(name + ": cannot continue it: its header differs from this run's: its records " +
                ((there & flag) != 0 ? "carry " : "do not carry ") + what + " (header flag bit " +
                (flag == detail::flagVelocities     ? "0"
                 : flag == detail::flagRegionRatios ? "1"
                                                    : "2") +
                ") but this run's " + ((here & flag) != 0 ? "do" : "do not") + " (" + key +
                "); run without --resume to start over");
  };
  differs(detail::flagRegionRatios, "region ratios", "output.regions");
  differs(detail::flagVelocities, "velocities", "output.velocities");
  differs(detail::flagContactForces, "contact forces", "output.contactForces");
}

}  // namespace

SimulationWriter::SimulationWriter(const std::filesystem::path& path, const SimulationFileHeader& header)
    : SimulationWriter(path, header, Options{}) {}

SimulationWriter::SimulationWriter(const std::filesystem::path& path, const SimulationFileHeader& header,
                                   Options options)
    : path_(path), header_(header), options_(options) {
  const std::string name = path.string();
  checkHeader(name, header);
  // Opened for reading too, so that a file deleted under the run can be written back, and
  // appending, so that a record written after something truncated the file lands at its
  // new end (where the next check sees it) instead of leaving a hole of zeros.
  const int fd = ::open(name.c_str(), O_RDWR | O_CREAT | O_TRUNC | O_APPEND | O_CLOEXEC, 0644);
  if (fd < 0) {
    throw Error(name + ": cannot create: " + systemMessage());
  }
  file_.reset(::fdopen(fd, "a+b"));
  if (!file_) {
    const std::string cause = systemMessage();
    ::close(fd);
    throw Error(name + ": cannot open: " + cause);
  }

  const std::vector<unsigned char> bytes = encodeHeader(header);
  if (std::fwrite(bytes.data(), 1, bytes.size(), file_.get()) != bytes.size() || std::fflush(file_.get()) != 0) {
    failWrite(name, "cannot write the header", errno);
  }
  buffer_.resize(static_cast<std::size_t>(header.recordBytes()));
}

SimulationWriter::SimulationWriter(const std::filesystem::path& path, const SimulationFileHeader& header,
                                   Options options, std::int64_t keepFrames, ContinueTag)
    : path_(path), header_(header), options_(options) {
  const std::string name = path.string();
  checkHeader(name, header);
  file_.reset(std::fopen(name.c_str(), "r+b"));
  if (!file_) {
    throw Error(name + ": cannot open to continue it: " + systemMessage());
  }
  const std::vector<unsigned char> expected = encodeHeader(header);
  std::vector<unsigned char> stored(expected.size(), 0);
  const bool whole = std::fread(stored.data(), 1, stored.size(), file_.get()) == stored.size();
  if (whole) checkSameFlags(name, stored.data(), header);
  if (!whole || stored != expected) {
    throw Error(name +
                ": cannot continue it: its header differs from this run's (vertex count, frame interval, "
                "timestep, velocity output or scene changed)");
  }
  if (::fseeko(file_.get(), 0, SEEK_END) != 0) {
    throw Error(name + ": cannot seek: " + systemMessage());
  }
  const auto size = static_cast<std::int64_t>(::ftello(file_.get()));
  const std::int64_t complete = (size - header.headerBytes()) / header.recordBytes();
  if (keepFrames < 0 || keepFrames > complete) {
    throw Error(name + ": cannot continue after frame " + std::to_string(keepFrames) + ": the file holds only " +
                std::to_string(complete) + " complete frames");
  }
  const std::int64_t keepBytes = header.headerBytes() + (keepFrames * header.recordBytes());
  const int fd = ::fileno(file_.get());
  if (std::fflush(file_.get()) != 0 || ::ftruncate(fd, static_cast<off_t>(keepBytes)) != 0 ||
      ::fseeko(file_.get(), static_cast<off_t>(keepBytes), SEEK_SET) != 0 ||
      ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) | O_APPEND) != 0) {
    throw Error(name + ": cannot cut the file after frame " + std::to_string(keepFrames) + ": " + systemMessage());
  }
  numFrames_ = keepFrames;
  buffer_.resize(static_cast<std::size_t>(header.recordBytes()));
}

std::unique_ptr<SimulationWriter> SimulationWriter::continueFile(const std::filesystem::path& path,
                                                                 const SimulationFileHeader& header,
                                                                 std::int64_t keepFrames, Options options) {
  return std::unique_ptr<SimulationWriter>(new SimulationWriter(path, header, options, keepFrames, ContinueTag{}));
}

SimulationWriter::~SimulationWriter() = default;

std::int64_t SimulationWriter::completeBytes() const {
  return header_.headerBytes() + (numFrames_ * header_.recordBytes());
}

void SimulationWriter::checkFileIntact(const std::string& where) {
  const int fd = ::fileno(file_.get());
  struct stat open {};
  if (::fstat(fd, &open) != 0) throw Error(where + ": cannot check the file: " + systemMessage());
  const std::int64_t expected = completeBytes();
  std::string problem;
  if (open.st_nlink == 0) {
    problem = "the file was deleted while the run was writing it; ";
    struct stat there {};
    if (::stat(path_.c_str(), &there) == 0) {
      problem += "another file is there now, so its " + framesText(numFrames_) + " are lost";
    } else if (copyBack(fd, path_, expected)) {
      problem += "its " + framesText(numFrames_) + " are written back to " + path_.string();
    } else {
      problem += "writing its " + framesText(numFrames_) + " back failed: " + systemMessage();
    }
  } else if (struct stat there{};
             ::stat(path_.c_str(), &there) != 0 || there.st_ino != open.st_ino || there.st_dev != open.st_dev) {
    problem = "the file was renamed or replaced while the run was writing it (" + framesText(numFrames_) +
              " are in the file this run opened)";
  } else if (static_cast<std::int64_t>(open.st_size) != expected) {
    problem = "the file is " + std::to_string(open.st_size) + " bytes, " + std::to_string(expected) +
              " expected: something else " + (open.st_size < expected ? "truncated" : "wrote to") +
              " it while the run was writing it; ";
  }
  if (problem.empty()) return;
  std::FILE* file = file_.release();
  __fpurge(file);
  std::fclose(file);
  if (problem.back() == ' ') {
    // What a reader still finds in the damaged file: the leading records that check out.
    try {
      SimulationReader reader(path_);
      problem += "it keeps " + framesText(reader.scanRecords().goodFrames) + " of " + std::to_string(numFrames_);
    } catch (const Error& error) {
      problem += std::string("no frame is readable (") + error.what() + ")";
    }
  }
  throw Error(where + ": " + problem);
}

void SimulationWriter::failWrite(const std::string& where, const std::string& what, int error) {
  // What stdio still buffers would land after the cut at fclose: drop it first.
  std::FILE* file = file_.release();
  __fpurge(file);
  // Never longer than it is (a header that failed leaves fewer bytes than it claims).
  struct stat now {};
  const bool sized = ::fstat(::fileno(file), &now) == 0;
  const std::int64_t keep = sized ? std::min<std::int64_t>(completeBytes(), now.st_size) : completeBytes();
  const bool regular = sized && S_ISREG(now.st_mode);  // not, e.g., /dev/full
  const bool cut = regular && ::ftruncate(::fileno(file), static_cast<off_t>(keep)) == 0;
  std::fclose(file);
  std::string message = where + ": " + what + ": " + std::strerror(error);
  if (!cut && (regular || !sized)) {
    message += " (and cutting the file back to its " + framesText(numFrames_) + " failed)";
  } else if (numFrames_ > 0) {
    message += "; the file keeps its " + framesText(numFrames_);
  }
  throw Error(message);
}

void SimulationWriter::close() {
  if (!file_) {
    return;
  }
  checkFileIntact(path_.string() + ": after frame " + std::to_string(numFrames_));
  std::FILE* file = file_.release();
  const bool flushed = std::fflush(file) == 0;
  const bool closed = std::fclose(file) == 0;
  if (!flushed || !closed) {
    throw Error(path_.string() + ": cannot close: " + systemMessage());
  }
}

void SimulationWriter::checkArraysGiven(bool velocity, bool ratios, bool contactForce) const {
  const std::string where = path_.string() + ": frame " + std::to_string(numFrames_) + ": ";
  if (header_.hasVelocities != velocity) {
    throw Error(where + (velocity ? "velocities given, but the file was created without them"
                                  : "the file stores velocities, but none were given"));
  }
  if (header_.hasRegionRatios != ratios) {
    throw Error(where + (ratios ? "region ratios given, but the file was created without them"
                                : "the file stores region ratios, but none were given"));
  }
  if (header_.hasContactForces != contactForce) {
    throw Error(where + (contactForce ? "contact forces given, but the file was created without them"
                                      : "the file stores contact forces, but none were given"));
  }
}

void SimulationWriter::appendFrame(double time, const Eigen::Ref<const Eigen::VectorXd>& displacement) {
  checkArraysGiven(false, false);
  appendRecord(time, displacement, nullptr, nullptr);
}

void SimulationWriter::appendFrame(double time, const Eigen::Ref<const Eigen::VectorXd>& displacement,
                                   const Eigen::Ref<const Eigen::VectorXd>& velocity) {
  checkArraysGiven(true, false);
  appendRecord(time, displacement, &velocity, nullptr);
}

void SimulationWriter::appendFrame(double time, const Eigen::Ref<const Eigen::VectorXd>& displacement,
                                   const std::vector<int>& ratios) {
  checkArraysGiven(false, true);
  appendRecord(time, displacement, nullptr, &ratios);
}

void SimulationWriter::appendFrame(double time, const Eigen::Ref<const Eigen::VectorXd>& displacement,
                                   const Eigen::Ref<const Eigen::VectorXd>& velocity, const std::vector<int>& ratios) {
  checkArraysGiven(true, true);
  appendRecord(time, displacement, &velocity, &ratios);
}

void SimulationWriter::appendFrame(double time, const Eigen::Ref<const Eigen::VectorXd>& displacement,
                                   const FrameArrays& arrays) {
  checkArraysGiven(arrays.velocity != nullptr, arrays.regionRatios != nullptr, arrays.contactForce != nullptr);
  std::optional<Eigen::Ref<const Eigen::VectorXd>> velocity, contactForce;
  if (arrays.velocity != nullptr) velocity.emplace(*arrays.velocity);
  if (arrays.contactForce != nullptr) contactForce.emplace(*arrays.contactForce);
  appendRecord(time, displacement, velocity ? &*velocity : nullptr, arrays.regionRatios,
               contactForce ? &*contactForce : nullptr);
}

void SimulationWriter::appendRecord(double time, const Eigen::Ref<const Eigen::VectorXd>& displacement,
                                    const Eigen::Ref<const Eigen::VectorXd>* velocity, const std::vector<int>* ratios,
                                    const Eigen::Ref<const Eigen::VectorXd>* contactForce) {
  const std::string where = path_.string() + ": frame " + std::to_string(numFrames_);
  if (!file_) {
    throw Error(where + ": the file is closed");
  }
  stopBeforeFrameIfAsked(numFrames_);
  checkFileIntact(where);
  const Eigen::Index size = 3 * header_.numVertices;
  if (displacement.size() != size || (velocity != nullptr && velocity->size() != size) ||
      (contactForce != nullptr && contactForce->size() != size)) {
    throw Error(where + ": expected vectors of size " + std::to_string(size) + ", got " +
                std::to_string(displacement.size()));
  }
  // A reader must be able to trust every frame it finds, so nothing non-finite is stored.
  if (!std::isfinite(time) || !displacement.allFinite() || (velocity != nullptr && !velocity->allFinite()) ||
      (contactForce != nullptr && !contactForce->allFinite())) {
    throw Error(where + ": refusing to store non-finite values");
  }
  if (ratios != nullptr) checkRatios(where, *ratios, header_.numVertices);

  unsigned char* out = buffer_.data();
  detail::putU64(out, static_cast<std::uint64_t>(numFrames_));
  detail::putF64(out + 8, time);
  std::size_t offset = detail::recordPrefixBytes;
  for (Eigen::Index i = 0; i < size; ++i, offset += 8) {
    detail::putF64(out + offset, displacement[i]);
  }
  if (velocity != nullptr) {
    for (Eigen::Index i = 0; i < size; ++i, offset += 8) {
      detail::putF64(out + offset, (*velocity)[i]);
    }
  }
  if (contactForce != nullptr) {
    for (Eigen::Index i = 0; i < size; ++i, offset += 8) {
      detail::putF64(out + offset, (*contactForce)[i]);
    }
  }
  if (ratios != nullptr) {
    std::memset(out + offset, 0, static_cast<std::size_t>(detail::regionRatioBytes(header_.numVertices)));
    for (std::size_t v = 0; v < ratios->size(); ++v) {
      detail::putU16(out + offset + (2 * v), static_cast<std::uint16_t>((*ratios)[v]));
    }
    offset += static_cast<std::size_t>(detail::regionRatioBytes(header_.numVertices));
  }
  detail::putU32(out + offset, crc32(out, offset));
  detail::putU32(out + offset + 4, 0);

  if (std::fwrite(out, 1, buffer_.size(), file_.get()) != buffer_.size() || std::fflush(file_.get()) != 0) {
    failWrite(where, "write failed", errno);
  }
  if (options_.syncEachFrame && ::fsync(::fileno(file_.get())) != 0) {
    failWrite(where, "fsync failed", errno);
  }
  takeBackIfInterleaved(where);
  ++numFrames_;
}

void SimulationWriter::takeBackIfInterleaved(const std::string& where) {
  // A change between checkFileIntact() and the write (e.g. a truncation while the record was
  // being encoded) put this record after foreign bytes: the append was the last write, so
  // cutting it off leaves the file as the other writer left it, and the change is reported.
  const int fd = ::fileno(file_.get());
  const auto record = static_cast<std::int64_t>(buffer_.size());
  struct stat after {};
  if (::fstat(fd, &after) != 0 || after.st_nlink == 0) return;  // a deleted file: the next check
  const auto size = static_cast<std::int64_t>(after.st_size);
  if (size == completeBytes() + record) return;
  if (size >= record && ::ftruncate(fd, static_cast<off_t>(size - record)) != 0) {
    throw Error(where + ": the file changed while this frame was written, and taking the frame back failed: " +
                systemMessage());
  }
  checkFileIntact(where);
}

}  // namespace asyncfem
