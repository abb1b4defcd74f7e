// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <string>

namespace asyncfem {

/// The complete state of a run after its last finished frame, enough to continue it and
/// produce exactly the bytes an uninterrupted run would have written (the layout is in
/// docs/simulation-output.md, "Checkpoint"):
///
///     offset  size  field
///          0     8  magic "AFEMCKP\0"
///          8     4  format version (u32, currently 3; version 1 has no monitor state,
///                   versions 1 and 2 no kept-factor state in backward Euler's internal state)
///         12     4  header size in bytes (u32, 64)
///         16     8  frames: finished frames, i.e. records 0 .. frames-1 of the output (i64)
///         24     8  simulated time t after those frames (f64)
///         32     8  numDofs: length of u and of v (u64, 3n)
///         40     8  internal-state length m (u64)
///         48     4  fingerprint of the run (u32, chosen by the writer of the file)
///         52     4  length L of the integrator name (u32, 1 to 64)
///         56     4  monitor-state length k (u32, at most 1024; 0 in version 1)
///         60     4  CRC-32 of bytes 0..59
///         64     L  integrator name, padded with zeros to a multiple of 8
///                   then u (numDofs f64), v (numDofs f64), internal state (m f64),
///                   monitor state (k f64), CRC-32 of every preceding byte (u32),
///                   reserved (u32, 0)
struct SimulationCheckpoint {
  std::int64_t frames = 0;        ///< finished frames (records 0 .. frames-1 of the output)
  double time = 0.0;              ///< simulated time after them
  std::uint32_t fingerprint = 0;  ///< identity of the run (scene, mesh, timestep), caller-defined
  std::string integrator;         ///< the integrator's name(), 1 to 64 characters
  Eigen::VectorXd displacement;   ///< u, size 3n
  Eigen::VectorXd velocity;       ///< v, size 3n
  /// Integrator::internalState(): what the next step needs beyond (u, v, t); may be empty.
  Eigen::VectorXd internalState;
  /// RunMonitor::state(): what the run's checks carry from frame to frame (the energy
  /// check's reference); may be empty.
  Eigen::VectorXd monitorState;
};

/// Current checkpoint format version. Version 3 has the layout of version 2; what changed
/// is what backward Euler with a kept factor stores as its internal state (the factor's
/// state, where version 2 had none: that run refactored at every frame). Versions 1 and 2
/// are still read (such a backward Euler run then refactors at its first step and says so).
inline constexpr std::uint32_t checkpointFileVersion = 3;

/// The checkpoint that belongs to an output file: the output's path with ".checkpoint"
/// appended ("run.afsim" -> "run.afsim.checkpoint").
std::filesystem::path checkpointPathFor(const std::filesystem::path& outputPath);

/// Writes the checkpoint atomically: to PATH.tmp, then renamed over PATH, so that PATH
/// always holds either the previous or the new checkpoint, complete, even if the process
/// is killed meanwhile. sync: also fsync the file before the rename (survives a machine
/// crash). Throws asyncfem::Error naming the file for write failures, non-finite values
/// or sizes that disagree (u, v must have the same size; the name 1 to 64 characters).
void writeCheckpoint(const std::filesystem::path& path, const SimulationCheckpoint& checkpoint, bool sync = false);

/// Reads and checks a checkpoint: magic, version, header CRC, sizes against the file size
/// (before anything is allocated from them), the CRC of the whole file, finite values.
/// Throws asyncfem::ParseError "PATH: message" for anything wrong, asyncfem::Error if the
/// file cannot be opened.
SimulationCheckpoint readCheckpoint(const std::filesystem::path& path);

/// Same checks on checkpoint bytes held in memory; name is used in messages.
SimulationCheckpoint parseCheckpoint(const unsigned char* data, std::size_t size, const std::string& name);

}  // namespace asyncfem
