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
  patchHeader(bytes, 40, 8, 8, true);  // unknown flags (bit 3; bits 0 to 2 are known)
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

// Records with region ratios (header flag bit 1).
SimulationFileHeader ratioHeader(int numVertices, bool velocities) {
  SimulationFileHeader header;
  header.numVertices = numVertices;
  header.frameInterval = 0.1;
  header.timestep = 0.025;
  header.hasVelocities = velocities;
  header.hasRegionRatios = true;
  return header;
}
// Frame k's ratios: a fast region that moves by one vertex per frame, and the largest ratio.
std::vector<int> ratiosOf(int numVertices, int k) {
  std::vector<int> ratios(static_cast<std::size_t>(numVertices), 1);
  ratios[static_cast<std::size_t>(k % numVertices)] = 8;
  ratios.back() = asyncfem::maxSimulationRegionRatio;
  return ratios;
}
Eigen::VectorXd valuesOf(int numVertices, int k) {
  return Eigen::VectorXd::LinSpaced(3 * numVertices, 0.25 * k, (0.25 * k) + 1.0);
}
// Writes three frames of 5 vertices (no velocities) to path.
void writeThreeFrames(const fs::path& path) {
  SimulationWriter writer(path, ratioHeader(5, false));
  for (int k = 0; k < 3; ++k) writer.appendFrame(0.1 * (k + 1), valuesOf(5, k), ratiosOf(5, k));
}
// Stores value (little-endian, size bytes) at offset.
void putBytes(std::vector<char>& bytes, std::size_t offset, std::uint64_t value, int size) {
  for (int i = 0; i < size; ++i) bytes[offset + static_cast<std::size_t>(i)] = static_cast<char>(value >> (8 * i));
}
// Gives the record at start (record bytes long) its correct checksum.
void fixRecordCrc(std::vector<char>& bytes, std::size_t start, std::size_t record) {
  putBytes(bytes, start + record - 8, asyncfem::crc32(bytes.data() + start, record - 8), 4);
}

TEST_F(SimulationFileTest, RoundTripIsBitExactWithAndWithoutVelocities) {
  for (const bool velocities : {false, true}) {
    const fs::path path = file(velocities ? "v.afsim" : "u.afsim");
    const int n = 5;
    {
      SimulationWriter writer(path, ratioHeader(n, velocities));
      for (int k = 0; k < 3; ++k) {
        if (velocities) {
          writer.appendFrame(0.1 * (k + 1), valuesOf(n, k), valuesOf(n, k + 7), ratiosOf(n, k));
        } else {
          writer.appendFrame(0.1 * (k + 1), valuesOf(n, k), ratiosOf(n, k));
        }
      }
    }
    // 16 + 24n (+ 24n) + the ratios, 2n = 10 bytes padded to 16, + 8: the documented layout.
    const std::int64_t record = 16 + (velocities ? 48 : 24) * n + 16 + 8;
    EXPECT_EQ(ratioHeader(n, velocities).recordBytes(), record);
    EXPECT_EQ(static_cast<std::int64_t>(fs::file_size(path)), 64 + 3 * record);
    SimulationReader reader(path);
    EXPECT_TRUE(reader.header().hasRegionRatios);
    EXPECT_EQ(reader.header().hasVelocities, velocities);
    ASSERT_EQ(reader.numFrames(), 3);
    for (int k = 0; k < 3; ++k) {
      const asyncfem::SimulationFrame frame = reader.readFrame(k);
      EXPECT_EQ(frame.displacement, valuesOf(n, k));  // stored bit for bit
      if (velocities) {
        EXPECT_EQ(frame.velocity, valuesOf(n, k + 7));
      }
      const std::vector<int> expected = ratiosOf(n, k);
      ASSERT_EQ(frame.regionRatios.size(), expected.size());
      for (std::size_t v = 0; v < expected.size(); ++v) EXPECT_EQ(frame.regionRatios[v], expected[v]) << v;
    }
  }
}

TEST_F(SimulationFileTest, FilesWithoutTheFlagCarryNoRatiosAndKeepTheirLayout) {
  const fs::path path = file("plain.afsim");
  SimulationFileHeader header = ratioHeader(4, false);
  header.hasRegionRatios = false;
  {
    SimulationWriter writer(path, header);
    writer.appendFrame(0.1, valuesOf(4, 0));
    EXPECT_THROW(writer.appendFrame(0.2, valuesOf(4, 1), ratiosOf(4, 1)), asyncfem::Error);
  }
  EXPECT_EQ(header.recordBytes(), 24 + 24 * 4);
  const std::vector<char> bytes = readBytes(path);
  EXPECT_EQ(bytes[40], 0);  // flags: none
  SimulationReader reader(path);
  EXPECT_FALSE(reader.header().hasRegionRatios);
  EXPECT_TRUE(reader.readFrame(0).regionRatios.empty());
}

TEST_F(SimulationFileTest, WriterRefusesMissingAndUnstorableRatios) {
  const fs::path path = file("refuse.afsim");
  SimulationWriter writer(path, ratioHeader(3, false));
  const auto messageOf = [&](const std::vector<int>& ratios) -> std::string {
    try {
      writer.appendFrame(0.1, valuesOf(3, 0), ratios);
    } catch (const asyncfem::Error& error) {
      return error.what();
    }
    return "";
  };
  EXPECT_NE(messageOf({1, 70000, 1})
                .find("frame 0: vertex 1: step ratio 70000 cannot be stored (a record holds "
                      "ratios from 1 to 65535)"),
            std::string::npos)
      << messageOf({1, 70000, 1});
  EXPECT_NE(messageOf({1, 1, 0}).find("vertex 2: step ratio 0"), std::string::npos);
  EXPECT_NE(messageOf({1, 1}).find("expected 3 region ratios, got 2"), std::string::npos);
  try {
    writer.appendFrame(0.1, valuesOf(3, 0));
    ADD_FAILURE() << "a frame without ratios was accepted";
  } catch (const asyncfem::Error& error) {
    EXPECT_NE(std::string(error.what()).find("the file stores region ratios, but none were given"), std::string::npos)
        << error.what();
  }
  EXPECT_EQ(writer.numFrames(), 0);
}

TEST_F(SimulationFileTest, ReaderNamesTheFrameAndVertexOfARatioOfZero) {
  const fs::path path = file("zero.afsim");
  writeThreeFrames(path);
  std::vector<char> bytes = readBytes(path);
  const std::size_t record = static_cast<std::size_t>(ratioHeader(5, false).recordBytes());
  const std::size_t frame2 = 64 + (2 * record);
  const std::size_t ratios = frame2 + 16 + (24 * 5);
  putBytes(bytes, ratios + (2 * 3), 0, 2);  // vertex 3's ratio (1) becomes 0
  fixRecordCrc(bytes, frame2, record);
  writeBytes(path, bytes);
  const std::string message = errorOf(path);
  EXPECT_NE(message.find("zero.afsim: frame 2: vertex 3 has region ratio 0 (step ratios are 1 or more)"),
            std::string::npos)
      << message;
  // Non-zero padding after the ratios (with a matching checksum) is refused too.
  putBytes(bytes, ratios + (2 * 3), 1, 2);
  putBytes(bytes, ratios + 12, 7, 1);
  fixRecordCrc(bytes, frame2, record);
  writeBytes(path, bytes);
  EXPECT_NE(errorOf(path).find("frame 2: the padding after the region ratios is not zero"), std::string::npos)
      << errorOf(path);
}

TEST_F(SimulationFileTest, ReaderRefusesARecordSizeThatIgnoresTheFlag) {
  const fs::path path = file("size.afsim");
  writeThreeFrames(path);
  std::vector<char> bytes = readBytes(path);
  // The record size of the same file without ratios, with a correct header checksum.
  patchHeader(bytes, 48, 24 + 24 * 5, 8, true);
  writeBytes(path, bytes);
  EXPECT_NE(errorOf(path).find("header record size 144 disagrees with 5 vertices with region ratios (expected 160)"),
            std::string::npos)
      << errorOf(path);
}

// The error continuing path's first frame under header gives ("" when it continues).
std::string continueRefusal(const fs::path& path, const SimulationFileHeader& header) {
  try {
    SimulationWriter::continueFile(path, header, 1, {});
  } catch (const asyncfem::Error& error) {
    return error.what();
  }
  return "";
}

TEST_F(SimulationFileTest, ContinuingKeepsTheRecordSizeAndRefusesAnotherFlag) {
  const fs::path path = file("continue.afsim");
  writeThreeFrames(path);
  {
    auto writer = SimulationWriter::continueFile(path, ratioHeader(5, false), 2, {});
    writer->appendFrame(0.3, valuesOf(5, 8), ratiosOf(5, 8));
    writer->close();
  }
  SimulationReader reader(path);
  EXPECT_EQ(reader.numFrames(), 3);
  EXPECT_FALSE(reader.hasTruncatedFrame());
  EXPECT_EQ(reader.readFrame(2).regionRatios[3], 8);  // ratiosOf(5, 8): vertex 8 % 5 fast
  SimulationFileHeader without = ratioHeader(5, false);
  without.hasRegionRatios = false;
  const std::string refusal = continueRefusal(path, without);
  EXPECT_NE(refusal.find("continue.afsim: cannot continue it: its header differs from this run's: its records carry "
                         "region ratios (header flag bit 1) but this run's do not (output.regions)"),
            std::string::npos)
      << refusal;
  EXPECT_EQ(SimulationReader(path).numFrames(), 3);  // untouched
}

// Records with contact forces (header flag bit 2): 3n doubles after the velocities and
// before the region ratios, each array stored bit for bit.
TEST_F(SimulationFileTest, ContactForcesRoundTripBetweenTheVelocitiesAndTheRatios) {
  const fs::path path = file("forces.afsim");
  const int n = 5;
  SimulationFileHeader header = ratioHeader(n, true);
  header.hasContactForces = true;
  {
    SimulationWriter writer(path, header);
    for (int k = 0; k < 2; ++k) {
      const Eigen::VectorXd u = valuesOf(n, k), v = valuesOf(n, k + 7), f = -valuesOf(n, k + 3);
      const std::vector<int> ratios = ratiosOf(n, k);
      writer.appendFrame(0.1 * (k + 1), u, asyncfem::FrameArrays{&v, &f, &ratios});
    }
    // Arrays that the header does not announce, or that it does and are missing, are refused.
    const Eigen::VectorXd u = valuesOf(n, 2), v = valuesOf(n, 9);
    const std::vector<int> ratios = ratiosOf(n, 2);
    EXPECT_THROW(writer.appendFrame(0.3, u, v, ratios), asyncfem::Error);
    const Eigen::VectorXd shortForce = Eigen::VectorXd::Zero(3 * n - 1);
    EXPECT_THROW(writer.appendFrame(0.3, u, asyncfem::FrameArrays{&v, &shortForce, &ratios}), asyncfem::Error);
    Eigen::VectorXd notFinite = valuesOf(n, 2);
    notFinite[4] = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(writer.appendFrame(0.3, u, asyncfem::FrameArrays{&v, &notFinite, &ratios}), asyncfem::Error);
    EXPECT_EQ(writer.numFrames(), 2);
  }
  // 16 + 3 arrays of 24n + the ratios (10 bytes padded to 16) + 8.
  EXPECT_EQ(header.recordBytes(), 16 + 72 * n + 16 + 8);
  EXPECT_EQ(static_cast<std::int64_t>(fs::file_size(path)), 64 + 2 * header.recordBytes());
  EXPECT_EQ(readBytes(path)[40], 7);  // flags: velocities, ratios, contact forces
  SimulationReader reader(path);
  EXPECT_TRUE(reader.header().hasContactForces);
  for (int k = 0; k < 2; ++k) {
    const asyncfem::SimulationFrame frame = reader.readFrame(k);
    EXPECT_EQ(frame.displacement, valuesOf(n, k));
    EXPECT_EQ(frame.velocity, valuesOf(n, k + 7));
    EXPECT_EQ(frame.contactForce, -valuesOf(n, k + 3));
    EXPECT_EQ(frame.regionRatios[static_cast<std::size_t>(k)], 8);
  }
  // A run that would not store them cannot continue the file: the flag is named.
  SimulationFileHeader without = header;
  without.hasContactForces = false;
  const std::string refusal = continueRefusal(path, without);
  EXPECT_NE(refusal.find("its records carry contact forces (header flag bit 2) but this run's do not "
                         "(output.contactForces)"),
            std::string::npos)
      << refusal;
  // A file without the flag reads no forces.
  const fs::path plain = file("plain-forces.afsim");
  { SimulationWriter(plain, ratioHeader(n, false)).appendFrame(0.1, valuesOf(n, 0), ratiosOf(n, 0)); }
  EXPECT_TRUE(SimulationReader(plain).readFrame(0).contactForce.size() == 0);
}

}  // namespace
