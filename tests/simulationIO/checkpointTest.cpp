// SPDX-License-Identifier: BSD-3-Clause
// The checkpoint next to a simulation output file, and continuing that file after a
// given frame (what offlineSimulator --resume relies on).
#include <gtest/gtest.h>
#include <unistd.h>

#include <asyncfem/core/error.hpp>
#include <asyncfem/simulationIO/checkpoint.hpp>
#include <asyncfem/simulationIO/crc32.hpp>
#include <asyncfem/simulationIO/simulationFile.hpp>
#include <bit>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using asyncfem::SimulationCheckpoint;

class CheckpointTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    directory_ = fs::temp_directory_path() /
                 ("asyncfem-checkpoint-" + std::string(info->name()) + "-" + std::to_string(::getpid()));
    fs::remove_all(directory_);
    fs::create_directories(directory_);
  }
  void TearDown() override { fs::remove_all(directory_); }

  static SimulationCheckpoint sample() {
    SimulationCheckpoint checkpoint;
    checkpoint.frames = 7;
    checkpoint.time = 0.35000000000000003;
    checkpoint.fingerprint = 0xdeadbeefU;
    checkpoint.integrator = "trapezoidal";
    checkpoint.displacement = Eigen::VectorXd::LinSpaced(12, -1.0, 1.0);
    checkpoint.displacement[0] = -0.0;
    checkpoint.displacement[1] = std::numeric_limits<double>::denorm_min();
    checkpoint.velocity = Eigen::VectorXd::LinSpaced(12, 3.0, -2.5);
    checkpoint.internalState = Eigen::VectorXd::Constant(12, 1.0 / 3.0);
    return checkpoint;
  }

  static std::vector<char> readBytes(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  }
  static void writeBytes(const fs::path& path, const std::vector<char>& bytes) {
    std::ofstream(path, std::ios::binary | std::ios::trunc)
        .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  }
  static std::string errorOf(const fs::path& path) {
    try {
      asyncfem::readCheckpoint(path);
    } catch (const asyncfem::ParseError& error) {
      return error.what();
    }
    return "no error";
  }

  fs::path directory_;
};

TEST_F(CheckpointTest, RoundTripIsExact) {
  const fs::path path = directory_ / "run.afsim.checkpoint";
  EXPECT_EQ(asyncfem::checkpointPathFor(directory_ / "run.afsim"), path);
  const SimulationCheckpoint written = sample();
  asyncfem::writeCheckpoint(path, written);
  EXPECT_FALSE(fs::exists(directory_ / "run.afsim.checkpoint.tmp"));  // renamed into place
  // 64 header + 16 name (11 padded) + 36 doubles + 8 suffix.
  EXPECT_EQ(fs::file_size(path), 64U + 16U + (36U * 8U) + 8U);
  const SimulationCheckpoint read = asyncfem::readCheckpoint(path);
  EXPECT_EQ(read.frames, 7);
  EXPECT_EQ(std::bit_cast<std::uint64_t>(read.time), std::bit_cast<std::uint64_t>(written.time));
  EXPECT_EQ(read.fingerprint, 0xdeadbeefU);
  EXPECT_EQ(read.integrator, "trapezoidal");
  ASSERT_EQ(read.displacement.size(), 12);
  EXPECT_EQ(std::memcmp(read.displacement.data(), written.displacement.data(), 12 * sizeof(double)), 0);
  EXPECT_TRUE(read.velocity == written.velocity);
  EXPECT_TRUE(read.internalState == written.internalState);

  // No internal state is fine too; a later checkpoint replaces the earlier one.
  SimulationCheckpoint plain = sample();
  plain.internalState.resize(0);
  plain.frames = 8;
  asyncfem::writeCheckpoint(path, plain);
  EXPECT_EQ(asyncfem::readCheckpoint(path).frames, 8);
  EXPECT_EQ(asyncfem::readCheckpoint(path).internalState.size(), 0);
}

TEST_F(CheckpointTest, MonitorStateRoundTripsAndVersionOneIsStillRead) {
  const fs::path path = directory_ / "monitor.checkpoint";
  SimulationCheckpoint written = sample();
  written.monitorState = Eigen::Vector3d(0.25, 1.5, 0.35);
  asyncfem::writeCheckpoint(path, written);
  // 64 header + 16 name + 39 doubles + 8 suffix.
  EXPECT_EQ(fs::file_size(path), 64U + 16U + (39U * 8U) + 8U);
  EXPECT_TRUE(asyncfem::readCheckpoint(path).monitorState == written.monitorState);
  written.monitorState = Eigen::VectorXd::Zero(1025);
  EXPECT_THROW(asyncfem::writeCheckpoint(path, written), asyncfem::Error);

  // A version 1 file (no monitor state; bytes 56..59 were reserved, 0) reads as before.
  SimulationCheckpoint old = sample();
  asyncfem::writeCheckpoint(path, old);
  std::vector<char> bytes = readBytes(path);
  bytes[8] = 1;
  const auto putCrc = [&](std::size_t offset, std::size_t length) {
    const std::uint32_t crc = asyncfem::crc32(bytes.data(), length);
    for (int b = 0; b < 4; ++b) bytes[offset + b] = static_cast<char>((crc >> (8 * b)) & 0xffU);
  };
  putCrc(60, 60);
  putCrc(bytes.size() - 8, bytes.size() - 8);
  writeBytes(path, bytes);
  const SimulationCheckpoint read = asyncfem::readCheckpoint(path);
  EXPECT_EQ(read.monitorState.size(), 0);
  EXPECT_TRUE(read.internalState == old.internalState);
  // Version 2 (no kept-factor state; the layout of version 3) reads as before too.
  bytes[8] = 2;
  putCrc(60, 60);
  putCrc(bytes.size() - 8, bytes.size() - 8);
  writeBytes(path, bytes);
  EXPECT_TRUE(asyncfem::readCheckpoint(path).internalState == old.internalState);
  bytes[8] = 4;
  putCrc(60, 60);
  writeBytes(path, bytes);
  EXPECT_NE(errorOf(path).find("unsupported checkpoint version 4"), std::string::npos) << errorOf(path);
  EXPECT_NE(errorOf(path).find("written by a newer AsyncFEM"), std::string::npos) << errorOf(path);
}

TEST_F(CheckpointTest, WriterRefusesBadCheckpoints) {
  const fs::path path = directory_ / "bad.checkpoint";
  SimulationCheckpoint checkpoint = sample();
  checkpoint.velocity[3] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(asyncfem::writeCheckpoint(path, checkpoint), asyncfem::Error);
  checkpoint = sample();
  checkpoint.velocity.resize(3);
  EXPECT_THROW(asyncfem::writeCheckpoint(path, checkpoint), asyncfem::Error);
  checkpoint = sample();
  checkpoint.integrator.clear();
  EXPECT_THROW(asyncfem::writeCheckpoint(path, checkpoint), asyncfem::Error);
  EXPECT_FALSE(fs::exists(path));
}

TEST_F(CheckpointTest, ReaderNamesWhatIsWrong) {
  const fs::path path = directory_ / "c.checkpoint";
  asyncfem::writeCheckpoint(path, sample());
  const std::vector<char> good = readBytes(path);

  std::vector<char> bytes = good;
  bytes.resize(40);
  writeBytes(path, bytes);
  EXPECT_NE(errorOf(path).find("truncated checkpoint: 40 bytes"), std::string::npos) << errorOf(path);

  bytes = good;
  bytes[3] = 'X';
  writeBytes(path, bytes);
  EXPECT_NE(errorOf(path).find("not an AsyncFEM checkpoint"), std::string::npos) << errorOf(path);

  bytes = good;
  bytes[20] = static_cast<char>(bytes[20] ^ 0x40);  // inside the frame count: header CRC
  writeBytes(path, bytes);
  EXPECT_NE(errorOf(path).find("checkpoint header checksum mismatch"), std::string::npos) << errorOf(path);

  bytes = good;
  bytes[200] = static_cast<char>(bytes[200] ^ 1);  // inside the state
  writeBytes(path, bytes);
  EXPECT_NE(errorOf(path).find("checkpoint checksum mismatch"), std::string::npos) << errorOf(path);

  bytes = good;
  bytes.pop_back();
  writeBytes(path, bytes);
  EXPECT_NE(errorOf(path).find("the file is truncated or corrupted"), std::string::npos) << errorOf(path);

  EXPECT_THROW(asyncfem::readCheckpoint(directory_ / "missing.checkpoint"), asyncfem::Error);
}

TEST_F(CheckpointTest, HugeClaimedSizesFailBeforeAllocating) {
  // A valid header (its CRC recomputed) claiming 3 * 10^12 state entries: rejected from
  // the sizes alone.
  const fs::path path = directory_ / "huge.checkpoint";
  asyncfem::writeCheckpoint(path, sample());
  std::vector<char> bytes = readBytes(path);
  const std::uint64_t claimed = 3000000000000ULL;
  for (int i = 0; i < 8; ++i) bytes[static_cast<std::size_t>(32 + i)] = static_cast<char>((claimed >> (8 * i)) & 0xFF);
  const std::uint32_t crc = asyncfem::crc32(bytes.data(), 60);
  for (int i = 0; i < 4; ++i) bytes[static_cast<std::size_t>(60 + i)] = static_cast<char>((crc >> (8 * i)) & 0xFF);
  writeBytes(path, bytes);
  EXPECT_NE(errorOf(path).find("checkpoint claims 3000000000000 state entries"), std::string::npos) << errorOf(path);
}

TEST_F(CheckpointTest, ContinueFileKeepsTheFirstFramesAndAppendsAfterThem) {
  const fs::path path = directory_ / "run.afsim";
  asyncfem::SimulationFileHeader header;
  header.numVertices = 2;
  header.frameInterval = 0.1;
  header.timestep = 0.01;
  {
    asyncfem::SimulationWriter writer(path, header);
    for (int k = 0; k < 5; ++k) writer.appendFrame(0.1 * (k + 1), Eigen::VectorXd::Constant(6, k));
  }
  // An interrupted append leaves a partial record behind.
  std::vector<char> bytes = readBytes(path);
  bytes.resize(bytes.size() + 17, '\x55');
  writeBytes(path, bytes);

  {
    auto writer = asyncfem::SimulationWriter::continueFile(path, header, 3, {});
    EXPECT_EQ(writer->numFrames(), 3);
    writer->appendFrame(0.4, Eigen::VectorXd::Constant(6, 30.0));
    writer->close();
  }
  asyncfem::SimulationReader reader(path);
  EXPECT_EQ(reader.numFrames(), 4);
  EXPECT_FALSE(reader.hasTruncatedFrame());
  reader.verifyAll();
  EXPECT_EQ(reader.readFrame(2).displacement[0], 2.0);
  EXPECT_EQ(reader.readFrame(3).displacement[0], 30.0);

  // More frames than the file holds, or another header: refused, file untouched.
  EXPECT_THROW(asyncfem::SimulationWriter::continueFile(path, header, 5, {}), asyncfem::Error);
  asyncfem::SimulationFileHeader other = header;
  other.hasVelocities = true;
  try {
    asyncfem::SimulationWriter::continueFile(path, other, 1, {});
    ADD_FAILURE() << "a different header was accepted";
  } catch (const asyncfem::Error& error) {
    EXPECT_NE(std::string(error.what()).find("its header differs from this run's"), std::string::npos) << error.what();
  }
  EXPECT_EQ(asyncfem::SimulationReader(path).numFrames(), 4);
}

}  // namespace
