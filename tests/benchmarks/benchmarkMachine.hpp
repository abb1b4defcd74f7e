// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// What every benchmark prints about the machine it ran on, so that its numbers are read
// with the CPU and the load they were measured under.
#include <fstream>
#include <string>

namespace asyncfem::bench {

/// The CPU's model name from /proc/cpuinfo ("unknown CPU" where there is none).
inline std::string cpuModel() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
  }
  return "unknown CPU";
}

/// The 1, 5 and 15 minute load averages from /proc/loadavg ("" where there are none).
inline std::string loadAverage() {
  std::ifstream in("/proc/loadavg");
  std::string a, b, c;
  in >> a >> b >> c;
  return a.empty() ? std::string() : a + " " + b + " " + c;
}

}  // namespace asyncfem::bench
