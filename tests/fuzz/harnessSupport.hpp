// SPDX-License-Identifier: BSD-3-Clause
// What the harnesses share (harnesses.cpp, sceneHarness.cpp): the scratch folder inputs go
// through, and turning a reader's run into an Outcome.
#pragma once

#include <asyncfem/core/error.hpp>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <filesystem>
#include <string>

#include "harnesses.hpp"

namespace asyncfem::fuzz {

/// A folder of this process, removed when it exits normally.
const std::filesystem::path& scratchFolder();
/// Writes the bytes to scratchFolder() / name; returns the path.
std::filesystem::path writeInput(const std::string& name, const std::uint8_t* data, std::size_t size);
/// A rejected input's summary: "ErrorClass: message", the scratch folder written "<scratch>".
std::string describe(const Error& error);
/// libFuzzer's finding: aborts on a crashed outcome (after printing it).
void abortOnCrash(const Outcome& outcome);

// Runs one reader (read() returns the summary of what it read): an asyncfem::Error is the
// documented rejection of bad input; any other exception is a finding.
template <typename Read>
Outcome classify(Read&& read) {
  try {
    return {OutcomeClass::accepted, read()};
  } catch (const Error& error) {
    return {OutcomeClass::rejected, describe(error)};
  } catch (const std::exception& error) {
    return {OutcomeClass::crashed, std::string("an exception not derived from asyncfem::Error: ") + error.what()};
  } catch (...) {
    return {OutcomeClass::crashed, "an exception not derived from std::exception"};
  }
}

}  // namespace asyncfem::fuzz
