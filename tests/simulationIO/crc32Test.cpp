// SPDX-License-Identifier: BSD-3-Clause
#include <gtest/gtest.h>

#include <asyncfem/simulationIO/crc32.hpp>
#include <string>

namespace {

TEST(Crc32, MatchesTheStandardCheckValue) {
  const std::string text = "123456789";
  EXPECT_EQ(asyncfem::crc32(text.data(), text.size()), 0xCBF43926U);
  EXPECT_EQ(asyncfem::crc32(nullptr, 0), 0U);
}

TEST(Crc32, ContinuesOverPieces) {
  const std::string text = "123456789";
  const std::uint32_t first = asyncfem::crc32(text.data(), 4);
  EXPECT_EQ(asyncfem::crc32(text.data() + 4, 5, first), 0xCBF43926U);
}

}  // namespace
