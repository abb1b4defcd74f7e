// SPDX-License-Identifier: BSD-3-Clause
#include "detail/textInput.hpp"

#include <asyncfem/core/error.hpp>
#include <asyncfem/volumetricMesh/writers.hpp>

#include <fstream>
#include <sstream>
#include <string>
#include <system_error>

namespace asyncfem {

namespace {

/// Prefix of the sets writeVeg adds only to give a material its *REGION; readVeg uses
/// them for materials and does not keep them as element sets.
constexpr std::string_view kMaterialSetPrefix = "__material_";

/// Writes text to a temporary file next to path and renames it over path, so readers
/// never see a half-written file.
void writeAtomically(const std::filesystem::path& path, const std::string& text) {
  std::filesystem::path temporary = path;
  temporary += ".tmp";
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    if (!out) throw Error("cannot write '" + path.string() + "': cannot create '" + temporary.string() + "'");
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
    out.flush();
    if (!out) {
      out.close();
      std::error_code ignored;
      std::filesystem::remove(temporary, ignored);
      throw Error("cannot write '" + path.string() + "': write failed (disk full?)");
    }
  }
  std::error_code ec;
  std::filesystem::rename(temporary, path, ec);
  if (ec) {
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    throw Error("cannot write '" + path.string() + "': " + ec.message());
  }
}

/// .veg names are single tokens: no whitespace, commas or '#', not starting with '*'.
void checkVegName(const std::string& name, const std::string& what) {
  bool ok = !name.empty() && name.front() != '*';
  for (char c : name) ok = ok && c != ',' && c != '#' && c != ' ' && c != '\t' && c != '\n' && c != '\r';
  if (!ok) throw ValidationError("writeVeg: " + what + " name '" + name + "' cannot be written to .veg (it must be one token without spaces, commas or '#')");
}

void writeIdList(std::ostringstream& out, const std::vector<int>& ids) {
  constexpr std::size_t kPerLine = 16;
  for (std::size_t i = 0; i < ids.size(); ++i) {
    out << ids[i] + 1 << (i + 1 == ids.size() ? "\n" : (i % kPerLine == kPerLine - 1 ? ",\n" : ", "));
  }
}

std::string xmlEscape(const std::string& text) {
  std::string escaped;
  for (char c : text) {
    switch (c) {
      case '&': escaped += "&amp;"; break;
      case '<': escaped += "&lt;"; break;
      case '>': escaped += "&gt;"; break;
      case '"': escaped += "&quot;"; break;
      default: escaped += c;
    }
  }
  return escaped;
}

void writeDataArray(std::ostringstream& out, const VtuArray& array, int count, const std::string& where) {
  if (array.name.empty()) throw ValidationError("writeVtu: a " + where + " array has no name");
  if (array.components != 1 && array.components != 3) {
    throw ValidationError("writeVtu: " + where + " array '" + array.name + "' has " + std::to_string(array.components) +
                          " components; only 1 or 3 are supported");
  }
  const std::size_t expected = static_cast<std::size_t>(array.components) * static_cast<std::size_t>(count);
  if (array.values.size() != expected) {
    throw ValidationError("writeVtu: " + where + " array '" + array.name + "' has " + std::to_string(array.values.size()) +
                          " values, expected " + std::to_string(expected));
  }
  out << "        <DataArray type=\"Float64\" Name=\"" << xmlEscape(array.name) << "\" NumberOfComponents=\""
      << array.components << "\" format=\"ascii\">\n";
  for (std::size_t i = 0; i < array.values.size(); i += static_cast<std::size_t>(array.components)) {
    out << "         ";
    for (int c = 0; c < array.components; ++c) out << ' ' << detail::formatDouble(array.values[i + static_cast<std::size_t>(c)]);
    out << '\n';
  }
  out << "        </DataArray>\n";
}

}  // namespace

void writeVeg(const std::filesystem::path& path, const TetMesh& mesh) {
  for (const Material& m : mesh.materials()) checkVegName(m.name, "material");
  for (const auto& [name, members] : mesh.elementSets()) {
    checkVegName(name, "element set");
    if (name.rfind(kMaterialSetPrefix, 0) == 0) {
      throw ValidationError("writeVeg: element set name '" + name + "' uses the reserved prefix " + std::string(kMaterialSetPrefix));
    }
  }
  for (const auto& [name, members] : mesh.vertexSets()) checkVegName(name, "vertex set");

  std::ostringstream out;
  out << "# " << mesh.numVertices() << " vertices, " << mesh.numElements() << " tetrahedra, "
      << mesh.materials().size() << " materials\n";
  out << "*VERTICES\n" << mesh.numVertices() << " 3 0 0\n";
  for (int v = 0; v < mesh.numVertices(); ++v) {
    const Eigen::Vector3d x = mesh.restPosition(v);
    out << v + 1 << ' ' << detail::formatDouble(x.x()) << ' ' << detail::formatDouble(x.y()) << ' '
        << detail::formatDouble(x.z()) << '\n';
  }
  out << "\n*ELEMENTS\nTET\n" << mesh.numElements() << " 4 0\n";
  for (int e = 0; e < mesh.numElements(); ++e) {
    const Eigen::Vector4i t = mesh.element(e);
    out << e + 1 << ' ' << t[0] + 1 << ' ' << t[1] + 1 << ' ' << t[2] + 1 << ' ' << t[3] + 1 << '\n';
  }
  for (const Material& m : mesh.materials()) {
    out << "\n*MATERIAL " << m.name << "\nENU, " << detail::formatDouble(m.density) << ", "
        << detail::formatDouble(m.youngsModulus) << ", " << detail::formatDouble(m.poissonRatio) << '\n';
  }
  for (const auto& [name, members] : mesh.elementSets()) {
    out << "\n*SET " << name << '\n';
    writeIdList(out, members);
  }
  for (const auto& [name, members] : mesh.vertexSets()) {
    out << "\n*VERTEXSET " << name << '\n';
    writeIdList(out, members);
  }

  // One *REGION line per material that has elements, naming an existing set with
  // exactly those elements when there is one, otherwise a helper set.
  std::vector<std::vector<int>> materialElements(mesh.materials().size());
  for (int e = 0; e < mesh.numElements(); ++e) materialElements[static_cast<std::size_t>(mesh.elementMaterialIndex(e))].push_back(e);
  std::string regions;
  for (std::size_t m = 0; m < materialElements.size(); ++m) {
    const std::vector<int>& members = materialElements[m];
    if (members.empty()) continue;
    std::string setName;
    const bool allElements = static_cast<int>(members.size()) == mesh.numElements();
    if (allElements && (!mesh.elementSets().count("allElements") || mesh.elementSets().at("allElements") == members)) {
      setName = "allElements";
    }
    for (const auto& [name, set] : mesh.elementSets()) {
      if (setName.empty() && set == members) setName = name;
    }
    if (setName.empty()) {
      setName = std::string(kMaterialSetPrefix) + mesh.materials()[m].name;
      out << "\n*SET " << setName << '\n';
      writeIdList(out, members);
    }
    regions += setName + ", " + mesh.materials()[m].name + '\n';
  }
  out << "\n*REGION\n" << regions;
  writeAtomically(path, out.str());
}

void writeVtu(const std::filesystem::path& path, const TetMesh& mesh, const Eigen::VectorXd& displacement,
              const std::vector<VtuArray>& pointArrays, const std::vector<VtuArray>& cellArrays) {
  if (displacement.size() != 0 && displacement.size() != mesh.numDofs()) {
    throw ValidationError("writeVtu: displacement has " + std::to_string(displacement.size()) + " entries, expected 0 or " +
                          std::to_string(mesh.numDofs()));
  }
  std::ostringstream out;
  out << "<?xml version=\"1.0\"?>\n"
      << "<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
      << "  <UnstructuredGrid>\n"
      << "    <Piece NumberOfPoints=\"" << mesh.numVertices() << "\" NumberOfCells=\"" << mesh.numElements() << "\">\n";
  out << "      <PointData>\n";
  if (displacement.size() != 0) {
    VtuArray u{"displacement", 3, std::vector<double>(displacement.data(), displacement.data() + displacement.size())};
    writeDataArray(out, u, mesh.numVertices(), "point");
  }
  for (const VtuArray& array : pointArrays) writeDataArray(out, array, mesh.numVertices(), "point");
  out << "      </PointData>\n      <CellData>\n";
  out << "        <DataArray type=\"Int32\" Name=\"material\" format=\"ascii\">\n";
  for (int e = 0; e < mesh.numElements(); ++e) out << (e % 16 == 0 ? "         " : "") << ' ' << mesh.elementMaterialIndex(e) << (e % 16 == 15 || e + 1 == mesh.numElements() ? "\n" : "");
  out << "        </DataArray>\n";
  for (const VtuArray& array : cellArrays) writeDataArray(out, array, mesh.numElements(), "cell");
  out << "      </CellData>\n      <Points>\n"
      << "        <DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n";
  for (int v = 0; v < mesh.numVertices(); ++v) {
    Eigen::Vector3d x = mesh.restPosition(v);
    if (displacement.size() != 0) x += displacement.segment<3>(3 * v);
    out << "          " << detail::formatDouble(x.x()) << ' ' << detail::formatDouble(x.y()) << ' '
        << detail::formatDouble(x.z()) << '\n';
  }
  out << "        </DataArray>\n      </Points>\n      <Cells>\n"
      << "        <DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">\n";
  for (int e = 0; e < mesh.numElements(); ++e) {
    const Eigen::Vector4i t = mesh.element(e);
    out << "          " << t[0] << ' ' << t[1] << ' ' << t[2] << ' ' << t[3] << '\n';
  }
  out << "        </DataArray>\n        <DataArray type=\"Int32\" Name=\"offsets\" format=\"ascii\">\n";
  for (int e = 0; e < mesh.numElements(); ++e) out << (e % 16 == 0 ? "         " : "") << ' ' << 4 * (e + 1) << (e % 16 == 15 || e + 1 == mesh.numElements() ? "\n" : "");
  out << "        </DataArray>\n        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";
  // VTK_TETRA = 10
  for (int e = 0; e < mesh.numElements(); ++e) out << (e % 16 == 0 ? "         " : "") << " 10" << (e % 16 == 15 || e + 1 == mesh.numElements() ? "\n" : "");
  out << "        </DataArray>\n      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n</VTKFile>\n";
  writeAtomically(path, out.str());
}

}  // namespace asyncfem
