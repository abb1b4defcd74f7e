// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>
#include <unistd.h>

#include <asyncfem/core/error.hpp>
#include <asyncfem/simulationIO/crc32.hpp>
#include <asyncfem/simulationIO/simulationFile.hpp>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using asyncfem::SimulationFileHeader;
using asyncfem::SimulationReader;
using asyncfem::SimulationWriter;

class SimulationFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    directory_ = fs::temp_directory_path() /
                 ("asyncfem-simulationIO-" + std::string(info->name()) + "-" + std::to_string(::getpid()));
    fs::remove_all(directory_);
    fs::create_directories(directory_);
  }
  void TearDown() override { fs::remove_all(directory_); }
  fs::path file(const std::string& name) const { return directory_ / name; }

  // Deterministic vectors whose values exercise every bit pattern class (negative zero,
  // subnormal, huge, tiny): a round trip must reproduce them exactly.
  static Eigen::VectorXd sample(int size, int seed) {
    Eigen::VectorXd v(size);
    for (int i = 0; i < size; ++i) {
      v[i] = std::sin((seed * 131.0) + i) * std::pow(10.0, (i % 7) - 3);
    }
    v[0] = -0.0;
    if (size > 2) {
      v[1] = std::numeric_limits<double>::denorm_min();
      v[2] = std::numeric_limits<double>::max();
    }
    return v;
  }

  // Writes `frames` sample frames of numVertices vertices, frame k at time interval (k + 1).
  static SimulationFileHeader writeSampleFrames(const fs::path& path, int numVertices, double interval, int frames) {
    SimulationFileHeader header;
    header.numVertices = numVertices;
    header.frameInterval = interval;
    SimulationWriter writer(path, header);
    for (int k = 0; k < frames; ++k) {
      writer.appendFrame(interval * (k + 1), sample(3 * numVertices, k));
    }
    return header;
  }

  static std::vector<char> readBytes(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  }
  static void writeBytes(const fs::path& path, const std::vector<char>& bytes) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  }

  static std::string errorOf(const fs::path& path) {
    try {
      SimulationReader reader(path);
      reader.verifyAll();
    } catch (const asyncfem::Error& error) {
      return error.what();
    }
    return "";
  }

  fs::path directory_;
};

bool bitEqual(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return a.size() == b.size() &&
         std::memcmp(a.data(), b.data(), static_cast<std::size_t>(a.size()) * sizeof(double)) == 0;
}

TEST_F(SimulationFileTest, RoundTripIsBitExact) {
  const fs::path path = file("roundTrip.afsim");
  SimulationFileHeader header;
  header.numVertices = 5;
  header.frameInterval = 1.0 / 30.0;
  header.timestep = 1.0 / 300.0;
  {
    SimulationWriter writer(path, header);
    for (int k = 0; k < 4; ++k) {
      writer.appendFrame((k + 1) * header.frameInterval, sample(15, k));
    }
    EXPECT_EQ(writer.numFrames(), 4);
  }
  EXPECT_EQ(static_cast<std::int64_t>(fs::file_size(path)), 64 + (4 * header.recordBytes()));

  SimulationReader reader(path);
  EXPECT_EQ(reader.numVertices(), 5);
  EXPECT_EQ(reader.header().frameInterval, header.frameInterval);
  EXPECT_EQ(reader.header().timestep, header.timestep);
  EXPECT_FALSE(reader.header().hasVelocities);
  ASSERT_EQ(reader.numFrames(), 4);
  EXPECT_FALSE(reader.hasTruncatedFrame());
  for (int k = 0; k < 4; ++k) {
    const asyncfem::SimulationFrame frame = reader.readFrame(k);
    EXPECT_EQ(frame.index, k);
    EXPECT_EQ(frame.time, (k + 1) * header.frameInterval);
    EXPECT_TRUE(bitEqual(frame.displacement, sample(15, k))) << "frame " << k;
    EXPECT_EQ(frame.velocity.size(), 0);
  }
}

TEST_F(SimulationFileTest, RoundTripWithVelocities) {
  const fs::path path = file("velocities.afsim");
  SimulationFileHeader header;
  header.numVertices = 3;
  header.frameInterval = 0.5;
  header.hasVelocities = true;
  {
    SimulationWriter writer(path, header, SimulationWriter::Options{true});
    writer.appendFrame(0.5, sample(9, 1), sample(9, 2));
    EXPECT_THROW(writer.appendFrame(1.0, sample(9, 1)), asyncfem::Error);
    writer.close();
  }
  SimulationReader reader(path);
  ASSERT_EQ(reader.numFrames(), 1);
  EXPECT_TRUE(reader.header().hasVelocities);
  const auto frame = reader.readFrame(0);
  EXPECT_TRUE(bitEqual(frame.displacement, sample(9, 1)));
  EXPECT_TRUE(bitEqual(frame.velocity, sample(9, 2)));
}

TEST_F(SimulationFileTest, WriterRejectsWrongSizesAndNonFiniteValues) {
  const fs::path path = file("rejects.afsim");
  SimulationFileHeader header;
  header.numVertices = 2;
  header.frameInterval = 0.1;
  SimulationWriter writer(path, header);
  EXPECT_THROW(writer.appendFrame(0.1, Eigen::VectorXd::Zero(5)), asyncfem::Error);
  Eigen::VectorXd bad = Eigen::VectorXd::Zero(6);
  bad[3] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(writer.appendFrame(0.1, bad), asyncfem::Error);
  writer.appendFrame(0.1, Eigen::VectorXd::Ones(6));
  EXPECT_EQ(writer.numFrames(), 1);
  SimulationReader reader(path);
  EXPECT_EQ(reader.numFrames(), 1);
}

TEST_F(SimulationFileTest, WriterTruncatesAnExistingFile) {
  const fs::path path = file("truncate.afsim");
  SimulationFileHeader header;
  header.numVertices = 2;
  header.frameInterval = 0.1;
  {
    SimulationWriter writer(path, header);
    for (int k = 0; k < 3; ++k) {
      writer.appendFrame(0.1 * k, Eigen::VectorXd::Ones(6));
    }
  }
  { SimulationWriter writer(path, header); }
  SimulationReader reader(path);
  EXPECT_EQ(reader.numFrames(), 0);
  EXPECT_FALSE(reader.hasTruncatedFrame());
}

TEST_F(SimulationFileTest, TruncatedLastFrameIsIgnoredAndReported) {
  const fs::path path = file("truncated.afsim");
  const SimulationFileHeader header = writeSampleFrames(path, 4, 0.25, 3);
  std::vector<char> bytes = readBytes(path);
  bytes.resize(bytes.size() - 17);  // cut into the last record
  writeBytes(path, bytes);

  SimulationReader reader(path);
  EXPECT_EQ(reader.numFrames(), 2);
  EXPECT_TRUE(reader.hasTruncatedFrame());
  EXPECT_EQ(reader.truncatedTrailingBytes(), header.recordBytes() - 17);
  EXPECT_NO_THROW(reader.verifyAll());
  EXPECT_TRUE(bitEqual(reader.readFrame(1).displacement, sample(12, 1)));
  EXPECT_THROW(reader.readFrame(2), asyncfem::Error);
}

TEST_F(SimulationFileTest, RefreshSeesFramesAppendedLater) {
  const fs::path path = file("live.afsim");
  SimulationFileHeader header;
  header.numVertices = 1;
  header.frameInterval = 1.0;
  SimulationWriter writer(path, header);
  SimulationReader reader(path);
  EXPECT_EQ(reader.numFrames(), 0);
  writer.appendFrame(1.0, Eigen::Vector3d(1, 2, 3));
  reader.refresh();
  ASSERT_EQ(reader.numFrames(), 1);
  EXPECT_EQ(reader.readFrame(0).displacement, Eigen::Vector3d(1, 2, 3));
}

TEST_F(SimulationFileTest, CorruptedRecordNamesTheFrame) {
  const fs::path path = file("corrupt.afsim");
  SimulationFileHeader header;
  header.numVertices = 2;
  header.frameInterval = 0.1;
  {
    SimulationWriter writer(path, header);
    for (int k = 0; k < 3; ++k) {
      writer.appendFrame(0.1 * k, sample(6, k));
    }
  }
  std::vector<char> bytes = readBytes(path);
  const std::size_t offset = 64 + (static_cast<std::size_t>(header.recordBytes()) * 1) + 20;
  bytes[offset] = static_cast<char>(bytes[offset] ^ 0x10);
  writeBytes(path, bytes);

  SimulationReader reader(path);
  EXPECT_EQ(reader.numFrames(), 3);
  EXPECT_NO_THROW(reader.readFrame(0));
  EXPECT_NO_THROW(reader.readFrame(2));
  try {
    reader.readFrame(1);
    FAIL() << "expected a checksum error";
  } catch (const asyncfem::ParseError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("frame 1"), std::string::npos) << message;
    EXPECT_NE(message.find("checksum"), std::string::npos) << message;
    EXPECT_NE(message.find(path.string()), std::string::npos) << message;
  }
}

TEST_F(SimulationFileTest, ScanReportsTheFirstBadRecordAndTheTimesBefore) {
  const fs::path path = file("scan.afsim");
  const SimulationFileHeader header = writeSampleFrames(path, 2, 0.1, 4);
  {
    SimulationReader reader(path);
    const asyncfem::RecordScan scan = reader.scanRecords();
    EXPECT_EQ(scan.goodFrames, 4);
    EXPECT_FALSE(scan.badFrame.has_value());
    EXPECT_EQ(scan.firstTime, 0.1);
    EXPECT_EQ(scan.lastTime, 0.4);
  }
  std::vector<char> bytes = readBytes(path);
  const std::size_t offset = 64 + (static_cast<std::size_t>(header.recordBytes()) * 2) + 20;
  bytes[offset] = static_cast<char>(bytes[offset] ^ 0x10);
  writeBytes(path, bytes);
  SimulationReader reader(path);
  const asyncfem::RecordScan scan = reader.scanRecords();
  EXPECT_EQ(scan.goodFrames, 2);
  ASSERT_TRUE(scan.badFrame.has_value());
  EXPECT_EQ(*scan.badFrame, 2);
  EXPECT_NE(scan.badMessage.find("frame 2"), std::string::npos) << scan.badMessage;
  EXPECT_EQ(scan.firstTime, 0.1);
  EXPECT_EQ(scan.lastTime, 0.2);
}

TEST_F(SimulationFileTest, BadMagicIsNamed) {
  const fs::path path = file("magic.afsim");
  writeBytes(path, std::vector<char>(200, 'x'));
  const std::string message = errorOf(path);
  EXPECT_NE(message.find("bad magic"), std::string::npos) << message;
  EXPECT_NE(message.find(path.string()), std::string::npos) << message;
}

TEST_F(SimulationFileTest, TruncatedHeaderIsNamed) {
  const fs::path path = file("short.afsim");
  SimulationFileHeader header;
  header.numVertices = 2;
  header.frameInterval = 0.1;
  { SimulationWriter writer(path, header); }
  std::vector<char> bytes = readBytes(path);
  bytes.resize(40);
  writeBytes(path, bytes);
  const std::string message = errorOf(path);
  EXPECT_NE(message.find("truncated header"), std::string::npos) << message;

  writeBytes(path, {});
  EXPECT_NE(errorOf(path).find("truncated header"), std::string::npos);
  EXPECT_NE(errorOf(file("missing.afsim")).find("cannot open"), std::string::npos);
}

// Rewrites a header field and, when asked, a correct header checksum, as a writer with
// different values (or a corrupted one) would have produced.
void patchHeader(std::vector<char>& bytes, std::size_t offset, std::uint64_t value, int size, bool fixCrc) {
  for (int i = 0; i < size; ++i) {
    bytes[offset + static_cast<std::size_t>(i)] = static_cast<char>(value >> (8 * i));
  }
  if (fixCrc) {
    const std::uint32_t crc = asyncfem::crc32(bytes.data(), 60);
    for (int i = 0; i < 4; ++i) {
      bytes[60 + static_cast<std::size_t>(i)] = static_cast<char>(crc >> (8 * i));
    }
  }
}

TEST_F(SimulationFileTest, AbsurdHeaderFailsFast) {
  const fs::path path = file("absurd.afsim");
  SimulationFileHeader header;
  header.numVertices = 2;
  header.frameInterval = 0.1;
  { SimulationWriter writer(path, header); }
  const std::vector<char> good = readBytes(path);

  std::vector<char> bytes = good;
  patchHeader(bytes, 16, std::uint64_t{1} << 60, 8, true);  // 2^60 vertices
  writeBytes(path, bytes);
  std::string message = errorOf(path);
  EXPECT_NE(message.find("vertices"), std::string::npos) << message;

  bytes = good;
  patchHeader(bytes, 16, 0, 8, true);
  writeBytes(path, bytes);
  EXPECT_NE(errorOf(path).find("claims 0 vertices"), std::string::npos);

  bytes = good;
  patchHeader(bytes, 48, 12345, 8, true);  // record size that disagrees with n
  writeBytes(path, bytes);
  EXPECT_NE(errorOf(path).find("record size"), std::string::npos);

  bytes = good;
  patchHeader(bytes, 40, 6, 8, true);  // unknown flags
  writeBytes(path, bytes);
  EXPECT_NE(errorOf(path).find("unknown flags"), std::string::npos);

  bytes = good;
  patchHeader(bytes, 8, 7, 4, true);
  writeBytes(path, bytes);
  EXPECT_NE(errorOf(path).find("unsupported format version 7"), std::string::npos);

  bytes = good;
  patchHeader(bytes, 16, 1000, 8, false);  // changed without a matching checksum
  writeBytes(path, bytes);
  message = errorOf(path);
  EXPECT_NE(message.find("header checksum mismatch"), std::string::npos) << message;
}

// docs/simulation-output.md states the record size as "### Frame record (`A + Bn` bytes,
// or `C + Dn` with velocities)" and the file as a 64-byte header plus records: files
// the writer produces must have exactly that size, so the page cannot drift from the code.
TEST_F(SimulationFileTest, FileSizeMatchesTheDocumentedLayout) {
  const fs::path page = fs::path(ASYNCFEM_MODELS_DIR).parent_path() / "docs" / "simulation-output.md";
  std::ifstream in(page);
  ASSERT_TRUE(in) << page;
  std::stringstream text;
  text << in.rdbuf();
  const std::string doc = text.str();
  std::smatch formula;
  const std::regex heading(R"(### Frame record \(`(\d+) \+ (\d+)n` bytes, or `(\d+) \+ (\d+)n` with velocities\))");
  ASSERT_TRUE(std::regex_search(doc, formula, heading)) << "record size heading not found in " << page;
  ASSERT_NE(doc.find("### Header (64 bytes)"), std::string::npos);
  ASSERT_NE(doc.find("Record `k` starts at byte `H + k * recordSize`"), std::string::npos);
  const std::int64_t fixed = std::stoll(formula[1]);
  const std::int64_t perVertex = std::stoll(formula[2]);
  const std::int64_t fixedWithVelocities = std::stoll(formula[3]);
  const std::int64_t perVertexWithVelocities = std::stoll(formula[4]);

  for (const bool velocities : {false, true}) {
    for (const int n : {1, 7}) {
      SimulationFileHeader header;
      header.numVertices = n;
      header.frameInterval = 0.1;
      header.hasVelocities = velocities;
      const fs::path path = file("layout.afsim");
      constexpr int frames = 3;
      {
        SimulationWriter writer(path, header);
        for (int k = 0; k < frames; ++k) {
          if (velocities) {
            writer.appendFrame(0.1 * (k + 1), sample(3 * n, k), sample(3 * n, k + 10));
          } else {
            writer.appendFrame(0.1 * (k + 1), sample(3 * n, k));
          }
        }
      }
      const std::int64_t record =
          velocities ? fixedWithVelocities + perVertexWithVelocities * n : fixed + perVertex * n;
      EXPECT_EQ(header.recordBytes(), record) << "n = " << n << ", velocities " << velocities;
      EXPECT_EQ(static_cast<std::int64_t>(fs::file_size(path)), 64 + frames * record)
          << "n = " << n << ", velocities " << velocities;
      // Record k starts at 64 + k * recordSize with its 8-byte index k.
      std::ifstream raw(path, std::ios::binary);
      for (std::int64_t k = 0; k < frames; ++k) {
        raw.seekg(64 + k * record);
        std::int64_t index = -1;
        raw.read(reinterpret_cast<char*>(&index), sizeof(index));  // little-endian host
        EXPECT_EQ(index, k);
      }
    }
  }
}

}  // namespace
