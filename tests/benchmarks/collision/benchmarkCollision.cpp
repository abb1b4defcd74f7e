// SPDX-License-Identifier: BSD-3-Clause
// Broad-phase cost per query (building the structure and finding every candidate pair) of
// Bullet's dynamic AABB tree, the uniform spatial hash and brute force, on the same surfaces
// and positions. Printed as a Markdown table; every time is the median wall time of
// repeated calls (at least --repeats and at least 0.5 s of them) after one untimed call,
// and every ratio compares two measurements of the same run. Brute force runs only up to --brute-force-limit triangles.
//
//   benchmarkCollision [--repeats 5] [--brute-force-limit 12000]
//
// Surfaces: tori of about 1k, 10k and 100k triangles with every vertex moved by uniform
// noise of a quarter of the mean edge length, against themselves (self-contact) and against
// a copy moved by a third of the tube radius (two bodies overlapping); and the boundary of
// makeBoxMesh cubes (1k and 10k triangles) against themselves. dhat is one tenth of the mean
// edge length.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <asyncfem/collision/broadPhase.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <cmath>
#include <cstdio>
#include <functional>
#include <numbers>
#include <optional>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "../benchmarkMachine.hpp"

namespace {

using namespace asyncfem;

struct Surface {
  std::string name;
  CollisionSurface surface;
  Eigen::Matrix3Xd positions;
};

/// A torus (radii 1 and 0.4) of around x aroundTube quads, two triangles each, with noise.
Surface torus(int around, int aroundTube, unsigned seed) {
  const int n = around * aroundTube;
  Eigen::Matrix3Xd positions(3, n);
  for (int i = 0; i < around; ++i) {
    const double u = 2.0 * std::numbers::pi * i / around;
    for (int j = 0; j < aroundTube; ++j) {
      const double v = 2.0 * std::numbers::pi * j / aroundTube;
      positions.col(i * aroundTube + j) = Eigen::Vector3d((1.0 + 0.4 * std::cos(v)) * std::cos(u),
                                                          (1.0 + 0.4 * std::cos(v)) * std::sin(u), 0.4 * std::sin(v));
    }
  }
  Eigen::Matrix3Xi triangles(3, 2 * n);
  for (int i = 0; i < around; ++i) {
    for (int j = 0; j < aroundTube; ++j) {
      const int a = i * aroundTube + j, b = ((i + 1) % around) * aroundTube + j;
      const int c = ((i + 1) % around) * aroundTube + (j + 1) % aroundTube, d = i * aroundTube + (j + 1) % aroundTube;
      triangles.col(2 * a) << a, b, c;
      triangles.col(2 * a + 1) << a, c, d;
    }
  }
  Surface result{"torus", triangleSurface(triangles, n), positions};
  double edgeLength = 0.0;
  for (int e = 0; e < result.surface.numEdges(); ++e)
    edgeLength += (positions.col(result.surface.edges(0, e)) - positions.col(result.surface.edges(1, e))).norm();
  edgeLength /= result.surface.numEdges();
  std::mt19937 generator(seed);
  std::uniform_real_distribution<double> noise(-0.25 * edgeLength, 0.25 * edgeLength);
  for (Eigen::Index k = 0; k < result.positions.size(); ++k) result.positions.data()[k] += noise(generator);
  return result;
}

Surface boxSurface(int cells) {
  BoxMeshSpec spec;
  spec.cells = Eigen::Vector3i::Constant(cells);
  const TetMesh mesh = makeBoxMesh(spec);
  return {"box mesh", boundarySurface(mesh), mesh.restPositions()};
}

double meanEdgeLength(const Surface& s) {
  double sum = 0.0;
  for (int e = 0; e < s.surface.numEdges(); ++e)
    sum += (s.positions.col(s.surface.edges(0, e)) - s.positions.col(s.surface.edges(1, e))).norm();
  return sum / s.surface.numEdges();
}

/// Median seconds of call() over at least `repeats` calls and at least 0.5 s of calls,
/// after one untimed call (small surfaces get many samples, so that a burst of load from
/// other processes moves the median little).
double medianSeconds(const std::function<void()>& call, int repeats) {
  call();
  std::vector<double> samples;
  double total = 0.0;
  while (static_cast<int>(samples.size()) < repeats || total < 0.5) {
    Stopwatch watch;
    watch.start();
    call();
    samples.push_back(watch.stop());
    total += samples.back();
  }
  std::sort(samples.begin(), samples.end());
  return samples[samples.size() / 2];
}

struct Scene {
  std::string name;
  const Surface* first;
  const Surface* second;  // null: self-contact
};

void measure(const Scene& scene, int repeats, int bruteForceLimit) {
  const double dhat = 0.1 * meanEdgeLength(*scene.first);
  auto query = [&](BroadPhaseMethod method) {
    return scene.second == nullptr
               ? findSelfContactCandidates(scene.first->surface, scene.first->positions, dhat, method)
               : findContactCandidates(scene.first->surface, scene.first->positions, scene.second->surface,
                                       scene.second->positions, dhat, method);
  };
  const std::size_t candidates = query(BroadPhaseMethod::SpatialHash).size();
  if (query(BroadPhaseMethod::DynamicTree).size() != candidates) std::fprintf(stderr, "methods disagree\n");
  const double tree = medianSeconds([&] { query(BroadPhaseMethod::DynamicTree); }, repeats);
  const double hash = medianSeconds([&] { query(BroadPhaseMethod::SpatialHash); }, repeats);
  std::optional<double> brute;
  if (scene.first->surface.numTriangles() <= bruteForceLimit)
    brute = medianSeconds([&] { query(BroadPhaseMethod::BruteForce); }, 1);
  char bruteText[32] = "-", bruteRatio[32] = "-";
  if (brute) {
    std::snprintf(bruteText, sizeof bruteText, "%.1f", 1e3 * *brute);
    std::snprintf(bruteRatio, sizeof bruteRatio, "%.1f", *brute / hash);
  }
  std::printf("| %s | %s | %d | %zu | %.2f | %.2f | %s | %.2f | %s |\n", scene.first->name.c_str(), scene.name.c_str(),
              scene.first->surface.numTriangles(), candidates, 1e3 * tree, 1e3 * hash, bruteText, tree / hash,
              bruteRatio);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Broad-phase time per query: dynamic AABB tree, spatial hash and brute force."};
  int repeats = 5;
  int bruteForceLimit = 12000;
  app.add_option("--repeats", repeats, "Timed calls per measurement (median)")->check(CLI::PositiveNumber);
  app.add_option("--brute-force-limit", bruteForceLimit, "Largest surface (triangles) brute force runs on");
  CLI11_PARSE(app, argc, argv);

  std::printf("Machine: %s, %u hardware threads, load %s; one thread (both methods are serial)\n\n",
              bench::cpuModel().c_str(), std::thread::hardware_concurrency(), bench::loadAverage().c_str());
  std::printf(
      "dhat = 0.1 x mean edge length; times in ms per query (build + find), median of >= %d calls and >= 0.5 s\n\n",
      repeats);
  std::printf(
      "| surface | scene | triangles | candidates | tree ms | hash ms | brute force ms | tree / hash | brute "
      "/ hash |\n");
  std::printf("|---|---|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const auto& [around, tube] : {std::pair{32, 16}, std::pair{100, 50}, std::pair{316, 158}}) {
    const Surface first = torus(around, tube, 1);
    Surface second = torus(around, tube, 2);
    second.positions.row(0).array() += 0.4 / 3.0;
    measure({"self", &first, nullptr}, repeats, bruteForceLimit);
    measure({"two bodies", &first, &second}, repeats, bruteForceLimit);
  }
  for (const int cells : {9, 29}) {
    const Surface box = boxSurface(cells);
    measure({"self", &box, nullptr}, repeats, bruteForceLimit);
  }
  return 0;
}
