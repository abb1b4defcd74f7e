// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/simulationIO/simulationFile.hpp>
#include <bit>
#include <cstdint>
#include <cstring>
#include <string>

namespace asyncfem::detail {

// The file is little-endian whatever the machine: values go through explicit byte
// shifts, which compilers turn into plain loads and stores on little-endian machines.

inline void putU32(unsigned char* out, std::uint32_t value) {
  for (int i = 0; i < 4; ++i) {
    out[i] = static_cast<unsigned char>(value >> (8 * i));
  }
}
inline void putU64(unsigned char* out, std::uint64_t value) {
  for (int i = 0; i < 8; ++i) {
    out[i] = static_cast<unsigned char>(value >> (8 * i));
  }
}
inline void putF64(unsigned char* out, double value) { putU64(out, std::bit_cast<std::uint64_t>(value)); }
inline void putU16(unsigned char* out, std::uint16_t value) {
  out[0] = static_cast<unsigned char>(value);
  out[1] = static_cast<unsigned char>(value >> 8);
}
inline std::uint16_t getU16(const unsigned char* in) {
  return static_cast<std::uint16_t>(in[0] | (static_cast<unsigned>(in[1]) << 8));
}

inline std::uint32_t getU32(const unsigned char* in) {
  std::uint32_t value = 0;
  for (int i = 0; i < 4; ++i) {
    value |= static_cast<std::uint32_t>(in[i]) << (8 * i);
  }
  return value;
}
inline std::uint64_t getU64(const unsigned char* in) {
  std::uint64_t value = 0;
  for (int i = 0; i < 8; ++i) {
    value |= static_cast<std::uint64_t>(in[i]) << (8 * i);
  }
  return value;
}
inline double getF64(const unsigned char* in) { return std::bit_cast<double>(getU64(in)); }

// Magic bytes at offset 0.
inline constexpr char simulationMagic[8] = {'A', 'F', 'E', 'M', 'S', 'I', 'M', '\0'};
inline constexpr std::uint64_t flagVelocities = 1;
inline constexpr std::uint64_t flagRegionRatios = 2;
inline constexpr std::uint64_t flagContactForces = 4;
inline constexpr std::uint64_t knownFlags = flagVelocities | flagRegionRatios | flagContactForces;

/// The flags a header's fields give.
inline std::uint64_t headerFlags(const SimulationFileHeader& header) {
  return (header.hasVelocities ? flagVelocities : 0) | (header.hasRegionRatios ? flagRegionRatios : 0) |
         (header.hasContactForces ? flagContactForces : 0);
}
/// Bytes of the region ratios of n vertices in a record: n u16, padded to a multiple of 8.
inline std::int64_t regionRatioBytes(std::int64_t numVertices) { return (2 * numVertices + 7) / 8 * 8; }

// Header field offsets (see simulationFile.hpp).
inline constexpr std::size_t offsetVersion = 8;
inline constexpr std::size_t offsetHeaderBytes = 12;
inline constexpr std::size_t offsetNumVertices = 16;
inline constexpr std::size_t offsetFrameInterval = 24;
inline constexpr std::size_t offsetTimestep = 32;
inline constexpr std::size_t offsetFlags = 40;
inline constexpr std::size_t offsetRecordBytes = 48;
inline constexpr std::size_t offsetHeaderCrc = 60;

// Record layout: index, time, values, CRC-32 of everything before it, 4 reserved bytes.
inline constexpr std::size_t recordPrefixBytes = 16;
inline constexpr std::size_t recordSuffixBytes = 8;

}  // namespace asyncfem::detail
