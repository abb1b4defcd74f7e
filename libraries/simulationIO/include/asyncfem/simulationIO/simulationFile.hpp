// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace asyncfem {

/// What the 64-byte header of a simulation output file (.afsim) says. The byte layout
/// (little-endian) is documented in docs/simulation-output.md:
///
///     offset  size  field
///          0     8  magic "AFEMSIM\0"
///          8     4  format version (u32, currently 1)
///         12     4  header size in bytes (u32, 64)
///         16     8  numVertices n (u64)
///         24     8  frame interval (f64, time between frames)
///         32     8  integrator timestep (f64, informational; 0 if unknown)
///         40     8  flags (u64): bit 0 = records carry velocities, bit 1 = records carry
///                   region ratios, bit 2 = records carry contact forces; other bits 0
///         48     8  record size in bytes (u64, derived from n and flags; checked)
///         56     4  reserved (0)
///         60     4  CRC-32 of bytes 0..59
///
/// Version 2 (written when the run names its scene) adds a scene block after byte 64, and
/// the header size at offset 12 covers it; frame records start after it:
///
///         64     4  scene fingerprint (u32, runMonitor's problemFingerprint of the run)
///         68     4  length L of the scene path (u32, 1 to 4096)
///         72     L  the scene file's absolute path, UTF-8, zero-padded to a multiple of 8
///     72+P(L)    4  CRC-32 of bytes 64 .. 72+P(L)-1
///     76+P(L)    4  reserved (0)
struct SimulationFileHeader {
  std::int64_t numVertices = 0;
  double frameInterval = 0.0;
  double timestep = 0.0;
  bool hasVelocities = false;
  /// Flag bit 1: each record also carries every vertex's step ratio to the large step (u16;
  /// 1 in the large-step region L, m_i in fast region S_i), for runs whose regions move.
  bool hasRegionRatios = false;
  /// Flag bit 2: each record also carries the contact force on every vertex (3n doubles,
  /// after the velocities), for runs that export them (scene key output.contactForces).
  bool hasContactForces = false;
  /// The scene the run came from (version 2; empty: none recorded, version 1), and the
  /// fingerprint of the mesh and fixed vertices it built, so that a reader can find the
  /// mesh by itself and tell when the scene has changed since.
  std::string scenePath;
  std::uint32_t sceneFingerprint = 0;

  /// Bytes before the first record: 64, or 64 + the scene block.
  std::int64_t headerBytes() const;

  /// Bytes of one frame record: index (8) + time (8) + 3n doubles of displacement
  /// (+ 3n of velocity) (+ 3n of contact force) (+ n u16 region ratios, zero-padded to a
  /// multiple of 8 bytes) +
  /// CRC-32 (4) + 4 reserved bytes.
  std::int64_t recordBytes() const;
};

/// Newest format version (2: with a scene block; files without one are written as
/// version 1, byte for byte as before), and the size of the fixed header in bytes.
inline constexpr std::uint32_t simulationFileVersion = 2;
inline constexpr std::int64_t simulationHeaderBytes = 64;
/// Longest scene path a header may carry.
inline constexpr std::size_t maxSimulationScenePath = 4096;
/// Largest vertex count a header may claim: 3n must fit in an int (Eigen index), so a
/// corrupt header can never trigger a giant allocation.
inline constexpr std::int64_t maxSimulationFileVertices = 715827882;  // floor((2^31 - 1) / 3)
/// Largest step ratio a record stores (u16); a writer refuses larger ones.
inline constexpr int maxSimulationRegionRatio = 65535;

/// One frame as stored: record index (0-based, consecutive), simulated time, and the
/// stacked 3n displacement (and velocity when the file carries them, else empty), and
/// each vertex's step ratio when the file carries region ratios (else empty).
struct SimulationFrame {
  std::int64_t index = 0;
  double time = 0.0;
  Eigen::VectorXd displacement;
  Eigen::VectorXd velocity;
  Eigen::VectorXd contactForce;  ///< 3n when the file carries contact forces, else empty
  std::vector<std::uint16_t> regionRatios;
};

/// The arrays of a frame record besides its displacement, each given exactly when the
/// header says the records carry it (null otherwise).
struct FrameArrays {
  const Eigen::VectorXd* velocity = nullptr;       ///< 3n
  const Eigen::VectorXd* contactForce = nullptr;   ///< 3n
  const std::vector<int>* regionRatios = nullptr;  ///< n
};

/// Writes a simulation output file. The constructor creates (or truncates) the file and
/// writes the header, so a run always starts from a fresh file; appendFrame() appends one
/// checksummed record and flushes it to the operating system before returning, so a
/// process killed at any point leaves every previously appended frame readable.
///
/// Errors (cannot create, write failure, wrong vector size, non-finite values) throw
/// asyncfem::Error naming the file. Storage faults (docs/robustness.md): a failed write
/// (a full file system, a file size limit) cuts the file back to its complete frames
/// before throwing; before every frame and at close() the writer checks that nothing else
/// deleted, replaced or truncated the file, and throws if something did (a deleted file
/// first gets its complete frames written back to the path). For tests only, the
/// environment variable ASYNCFEM_TEST_STOP_BEFORE_FRAME=K stops the process with SIGSTOP
/// before frame K is checked and appended (unset: no effect; docs/robustness.md).
class SimulationWriter {
 public:
  struct Options {
    /// Also fsync() after every frame, so frames survive a machine crash, not only a
    /// killed process (slower).
    bool syncEachFrame = false;
  };

  SimulationWriter(const std::filesystem::path& path, const SimulationFileHeader& header);
  SimulationWriter(const std::filesystem::path& path, const SimulationFileHeader& header, Options options);
  ~SimulationWriter();

  /// Continues the file an earlier run left at path (for restarting an interrupted run):
  /// its 64-byte header must be exactly the one `header` describes; its first keepFrames
  /// complete records are kept, everything after them (an interrupted append, frames
  /// past the last checkpoint) is cut off, and appendFrame() continues with frame
  /// keepFrames. Throws asyncfem::Error naming the file if it cannot be opened, its
  /// header differs (a differing flag, e.g. region ratios, is named), or it holds fewer
  /// than keepFrames complete records.
  static std::unique_ptr<SimulationWriter> continueFile(const std::filesystem::path& path,
                                                        const SimulationFileHeader& header, std::int64_t keepFrames,
                                                        Options options);
  SimulationWriter(const SimulationWriter&) = delete;
  SimulationWriter& operator=(const SimulationWriter&) = delete;

  /// Appends the next frame (index = numFrames()). displacement: size 3n. Use the
  /// overload with velocity when the header says hasVelocities.
  void appendFrame(double time, const Eigen::Ref<const Eigen::VectorXd>& displacement);
  void appendFrame(double time, const Eigen::Ref<const Eigen::VectorXd>& displacement,
                   const Eigen::Ref<const Eigen::VectorXd>& velocity);
  /// The same for a file whose header says hasRegionRatios: ratios holds every vertex's
  /// step ratio (n values, 1 to maxSimulationRegionRatio; others are refused naming the
  /// frame and the vertex).
  void appendFrame(double time, const Eigen::Ref<const Eigen::VectorXd>& displacement, const std::vector<int>& ratios);
  void appendFrame(double time, const Eigen::Ref<const Eigen::VectorXd>& displacement,
                   const Eigen::Ref<const Eigen::VectorXd>& velocity, const std::vector<int>& ratios);
  /// Any combination of arrays, as the header says (the only overload for a file with
  /// contact forces).
  void appendFrame(double time, const Eigen::Ref<const Eigen::VectorXd>& displacement, const FrameArrays& arrays);

  /// Frames appended so far.
  std::int64_t numFrames() const { return numFrames_; }
  /// False after close() and after a storage fault closed the file (the error said what
  /// the file holds then).
  bool isOpen() const { return file_ != nullptr; }
  const SimulationFileHeader& header() const { return header_; }
  const std::filesystem::path& path() const { return path_; }
  /// Checks that the file is still the one this writer created, at its full length,
  /// then flushes and closes; further appends throw. The destructor closes too
  /// (silently, without the check).
  void close();

 private:
  struct FileCloser {
    void operator()(std::FILE* file) const;
  };
  struct ContinueTag {};
  SimulationWriter(const std::filesystem::path& path, const SimulationFileHeader& header, Options options,
                   std::int64_t keepFrames, ContinueTag);
  /// Throws naming the frame when the arrays given (velocity, ratios) are not the ones the
  /// header says the records carry.
  void checkArraysGiven(bool velocity, bool ratios, bool contactForce = false) const;
  void appendRecord(double time, const Eigen::Ref<const Eigen::VectorXd>& displacement,
                    const Eigen::Ref<const Eigen::VectorXd>* velocity, const std::vector<int>* ratios,
                    const Eigen::Ref<const Eigen::VectorXd>* contactForce = nullptr);
  /// Bytes of the header and the complete frames written so far.
  std::int64_t completeBytes() const;
  /// Throws (and closes the file) when something else deleted, replaced or truncated the
  /// file since the last frame; a deleted file gets its complete frames written back.
  void checkFileIntact(const std::string& where);
  /// After a frame's write: when the file is not the complete frames plus this record
  /// (something changed it between the check and the write), cuts the record back off and
  /// throws as checkFileIntact() does.
  void takeBackIfInterleaved(const std::string& where);
  /// After a failed write: drops what is buffered, cuts the file back to its complete
  /// frames, closes it and throws naming the cause.
  [[noreturn]] void failWrite(const std::string& where, const std::string& what, int error);

  std::filesystem::path path_;
  SimulationFileHeader header_;
  Options options_;
  std::unique_ptr<std::FILE, FileCloser> file_;
  std::int64_t numFrames_ = 0;
  std::vector<unsigned char> buffer_;
};

/// Reads a simulation output file, possibly one still being written or left behind by an
/// interrupted run.
///
/// What SimulationReader::scanRecords() found: the times of the first and the last
/// frame read and, when a record failed its checks, which one and why.
struct RecordScan {
  std::int64_t goodFrames = 0;           ///< frames read before the first bad one (all when none is bad)
  double firstTime = 0.0;                ///< time of frame 0 (0 when it is bad or there is none)
  double lastTime = 0.0;                 ///< time of the last good frame (0 when there is none)
  std::optional<std::int64_t> badFrame;  ///< the first frame that failed its checks
  std::string badMessage;                ///< the ParseError's message for it
};

/// The constructor validates the header and throws asyncfem::ParseError naming the file
/// for a missing or truncated header, bad magic, an unsupported version, a header
/// checksum mismatch, unknown flags, or absurd sizes (n = 0, n > maxSimulationFileVertices,
/// a non-finite or negative frame interval, a record size that disagrees with n and the
/// flags). A trailing partial record (an interrupted append) is not an error: it is
/// ignored and reported by truncatedTrailingBytes(). readFrame() verifies the record's
/// checksum and index (and that every region ratio is at least 1) and throws a ParseError
/// naming the frame (and the vertex) if they do not match.
class SimulationReader {
 public:
  explicit SimulationReader(const std::filesystem::path& path);
  ~SimulationReader();
  SimulationReader(const SimulationReader&) = delete;
  SimulationReader& operator=(const SimulationReader&) = delete;

  const SimulationFileHeader& header() const { return header_; }
  const std::filesystem::path& path() const { return path_; }
  int numVertices() const { return static_cast<int>(header_.numVertices); }
  /// Complete frame records in the file (as of construction or the last refresh()).
  std::int64_t numFrames() const { return numFrames_; }
  /// Bytes after the last complete record: > 0 when the last append was interrupted.
  std::int64_t truncatedTrailingBytes() const { return trailingBytes_; }
  bool hasTruncatedFrame() const { return trailingBytes_ > 0; }

  /// Re-reads the file size (for a file another process is still appending to).
  void refresh();

  /// Frame k in [0, numFrames()).
  SimulationFrame readFrame(std::int64_t k);
  /// Same, reusing out's storage.
  void readFrame(std::int64_t k, SimulationFrame& out);
  /// Reads and checks every complete frame; throws at the first bad one.
  void verifyAll();
  /// Reads and checks every complete frame in order and stops at the first bad one,
  /// reporting it in the result instead of throwing.
  RecordScan scanRecords();

 private:
  struct FileCloser {
    void operator()(std::FILE* file) const;
  };
  void readSceneBlock(std::uint32_t headerBytes);

  std::filesystem::path path_;
  std::unique_ptr<std::FILE, FileCloser> file_;
  SimulationFileHeader header_;
  std::int64_t numFrames_ = 0;
  std::int64_t trailingBytes_ = 0;
  std::vector<unsigned char> buffer_;
};

}  // namespace asyncfem
