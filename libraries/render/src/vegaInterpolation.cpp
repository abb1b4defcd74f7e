// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/core/error.hpp>
#include <asyncfem/render/vegaInterpolation.hpp>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace asyncfem {

namespace {

std::ifstream openText(const std::filesystem::path& path, const char* what) {
  std::ifstream in(path);
  if (!in) throw Error(path.string() + ": cannot open the " + std::string(what));
  return in;
}

bool skippable(const std::string& line) {
  const std::size_t first = line.find_first_not_of(" \t\r");
  return first == std::string::npos || line[first] == '#';
}

// The vertex of one OBJ face corner ("12", "12/3", "12//4", "-1/2/3") as a 0-based id.
int objCorner(const std::string& token, int numVertices, const std::string& file, std::size_t line) {
  const std::string head = token.substr(0, token.find('/'));
  std::size_t used = 0;
  int id = 0;
  try {
    id = std::stoi(head, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != head.size() || id == 0) {
    throw ParseError(file, line, "face corner \"" + token + "\" is not a vertex id");
  }
  const int vertex = id > 0 ? id - 1 : numVertices + id;
  if (vertex < 0 || vertex >= numVertices) {
    throw ParseError(
        file, line,
        "face names vertex " + std::to_string(id) + " but " + std::to_string(numVertices) + " vertices precede it");
  }
  return vertex;
}

// An id as read (a number that may not be a whole one).
std::string formatId(double id) {
  std::ostringstream out;
  out << id;
  return out.str();
}

}  // namespace

SurfaceMesh readObjInFileOrder(const std::filesystem::path& path) {
  std::ifstream in = openText(path, "render mesh");
  const std::string file = path.string();
  std::vector<Eigen::Vector3d> vertices;
  SurfaceMesh surface;
  std::string text;
  for (std::size_t line = 1; std::getline(in, text); ++line) {
    std::istringstream fields(text);
    std::string kind;
    fields >> kind;
    if (kind == "v") {
      Eigen::Vector3d x;
      if (!(fields >> x.x() >> x.y() >> x.z()) || !x.allFinite()) {
        throw ParseError(file, line, "expected \"v x y z\" with finite coordinates");
      }
      vertices.push_back(x);
    } else if (kind == "f") {
      std::vector<int> corners;
      for (std::string token; fields >> token;) {
        corners.push_back(objCorner(token, static_cast<int>(vertices.size()), file, line));
      }
      if (corners.size() < 3) throw ParseError(file, line, "a face needs at least 3 vertices");
      for (std::size_t k = 1; k + 1 < corners.size(); ++k) {
        surface.triangles.push_back({corners[0], corners[k], corners[k + 1]});
      }
    }
  }
  if (surface.triangles.empty()) throw ParseError(file, 0, "holds no face");
  surface.vertices.resize(3, static_cast<Eigen::Index>(vertices.size()));
  for (std::size_t k = 0; k < vertices.size(); ++k) surface.vertices.col(static_cast<Eigen::Index>(k)) = vertices[k];
  return surface;
}

VegaInterpolation readVegaInterpolation(const std::filesystem::path& path, int numRenderVertices, int numTetVertices) {
  std::ifstream in = openText(path, ".interp file");
  const std::string file = path.string();
  VegaInterpolation result;
  result.vertices.resize(4, numRenderVertices);
  result.weights.resize(4, numRenderVertices);
  int count = 0;
  std::string text;
  for (std::size_t line = 1; std::getline(in, text); ++line) {
    if (skippable(text)) continue;
    std::istringstream fields(text);
    std::vector<double> numbers;
    for (std::string token; fields >> token;) {
      char* end = nullptr;
      const double value = std::strtod(token.c_str(), &end);
      if (end == token.c_str() || *end != '\0') throw ParseError(file, line, "\"" + token + "\" is not a number");
      numbers.push_back(value);
    }
    if (numbers.size() == 17) {
      throw ParseError(file, line, "8 (vertex, weight) pairs: weights in a cube mesh; only tet meshes are supported");
    }
    if (numbers.size() != 9) {
      throw ParseError(file, line,
                       "expected a vertex index and 4 (tet vertex, weight) pairs, got " +
                           std::to_string(numbers.size()) + " numbers");
    }
    if (numbers[0] != count) {
      throw ParseError(file, line,
                       "render vertex " + text.substr(0, text.find_first_of(" \t")) + " where vertex " +
                           std::to_string(count) + " comes next (one line per vertex, in order)");
    }
    if (count >= numRenderVertices) {
      throw ParseError(file, line,
                       "more lines than the render mesh's " + std::to_string(numRenderVertices) + " vertices");
    }
    double sum = 0.0;
    for (int a = 0; a < 4; ++a) {
      const double id = numbers[static_cast<std::size_t>(1 + 2 * a)];
      const double weight = numbers[static_cast<std::size_t>(2 + 2 * a)];
      if (id != std::floor(id) || id < 0 || id >= numTetVertices) {
        throw ParseError(file, line,
                         "tet vertex " + formatId(id) + " out of range [0, " + std::to_string(numTetVertices) +
                             ") (ids are 0-based)");
      }
      if (!std::isfinite(weight)) throw ParseError(file, line, "weight " + std::to_string(a) + " is not finite");
      result.vertices(a, count) = static_cast<int>(id);
      result.weights(a, count) = weight;
      sum += weight;
    }
    if (std::abs(sum - 1.0) > vegaInterpolationSumTolerance) {
      throw ParseError(file, line, "weights sum to " + std::to_string(sum) + ", not 1");
    }
    ++count;
  }
  if (count != numRenderVertices) {
    throw ParseError(file, 0,
                     "weights for " + std::to_string(count) + " vertices, but the render mesh has " +
                         std::to_string(numRenderVertices));
  }
  return result;
}

SurfaceEmbedding embedWithVegaInterpolation(const TetMesh& mesh, const std::filesystem::path& renderMesh,
                                            const std::filesystem::path& interpolation) {
  SurfaceMesh surface = readObjInFileOrder(renderMesh);
  const auto m = static_cast<int>(surface.vertices.cols());
  VegaInterpolation weights = readVegaInterpolation(interpolation, m, mesh.numVertices());
  return SurfaceEmbedding::withWeights(mesh.numVertices(), std::move(surface), std::move(weights.vertices),
                                       std::move(weights.weights));
}

}  // namespace asyncfem
