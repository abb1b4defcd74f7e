// SPDX-License-Identifier: BSD-3-Clause
#include <asyncfem/core/error.hpp>
#include <asyncfem/volumetricMesh/writers.hpp>
#include <bit>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <system_error>
#include <type_traits>
#include <utility>

#include "detail/textInput.hpp"

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
  if (!ok) {
    // Sets come from other formats (Gmsh group names may have spaces); meshInfo renames them.
    const std::string hint = what == "material" ? "" : "; rename it with meshInfo --rename-set '" + name + "=NEW'";
    throw ValidationError("writeVeg: " + what + " name '" + name +
                          "' cannot be written to .veg (it must be one token without spaces, commas or '#')" + hint);
  }
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
      case '&':
        escaped += "&amp;";
        break;
      case '<':
        escaped += "&lt;";
        break;
      case '>':
        escaped += "&gt;";
        break;
      case '"':
        escaped += "&quot;";
        break;
      default:
        escaped += c;
    }
  }
  return escaped;
}

/// Checks a user array's name, component count and size against count points or cells.
void checkArray(const VtuArray& array, int count, const std::string& where) {
  if (array.name.empty()) throw ValidationError("writeVtu: a " + where + " array has no name");
  if (array.components != 1 && array.components != 3) {
    throw ValidationError("writeVtu: " + where + " array '" + array.name + "' has " + std::to_string(array.components) +
                          " components; only 1 or 3 are supported");
  }
  const std::size_t expected = static_cast<std::size_t>(array.components) * static_cast<std::size_t>(count);
  if (array.values.size() != expected) {
    throw ValidationError("writeVtu: " + where + " array '" + array.name + "' has " +
                          std::to_string(array.values.size()) + " values, expected " + std::to_string(expected));
  }
}

/// The XML of a .vtu and, for the binary encoding, its appended block: each DataArray
/// either holds its values as text or points (offset) into the appended block, where it
/// is stored as a UInt64 byte count followed by the raw values.
class VtuBuilder {
 public:
  static_assert(sizeof(int) == 4, "mesh indices are written as VTK Int32");

  explicit VtuBuilder(VtuEncoding encoding) : encoding_(encoding) {}

  std::ostringstream& xml() { return xml_; }

  /// One DataArray of count values (tuples of `components`); name may be empty.
  template <typename T>
  void array(const char* type, const std::string& name, int components, const T* values, std::size_t count) {
    xml_ << "        <DataArray type=\"" << type << '"';
    if (!name.empty()) xml_ << " Name=\"" << xmlEscape(name) << '"';
    if (components != 1) xml_ << " NumberOfComponents=\"" << components << '"';
    if (encoding_ == VtuEncoding::binary) {
      xml_ << " format=\"appended\" offset=\"" << appended_.size() << "\"/>\n";
      const std::uint64_t bytes = count * sizeof(T);
      appendBytes(&bytes, sizeof(bytes));
      appendBytes(values, bytes);
      return;
    }
    xml_ << " format=\"ascii\">\n";
    // One tuple per line for vectors, 16 scalars per line otherwise.
    const std::size_t perLine = components == 1 ? 16 : static_cast<std::size_t>(components);
    for (std::size_t i = 0; i < count; ++i) {
      xml_ << (i % perLine == 0 ? "         " : "") << ' ';
      if constexpr (std::is_floating_point_v<T>) {
        xml_ << detail::formatDouble(values[i]);
      } else {
        xml_ << static_cast<long long>(values[i]);
      }
      if (i % perLine == perLine - 1 || i + 1 == count) xml_ << '\n';
    }
    xml_ << "        </DataArray>\n";
  }

  /// The finished file: XML, then (binary) the appended block.
  std::string finish() {
    if (encoding_ == VtuEncoding::binary) {
      xml_ << "  <AppendedData encoding=\"raw\">\n   _";
      xml_.write(appended_.data(), static_cast<std::streamsize>(appended_.size()));
      xml_ << "\n  </AppendedData>\n";
    }
    xml_ << "</VTKFile>\n";
    return xml_.str();
  }

 private:
  void appendBytes(const void* data, std::size_t bytes) {
    const auto* begin = static_cast<const char*>(data);
    appended_.append(begin, begin + bytes);
  }

  VtuEncoding encoding_;
  std::ostringstream xml_;
  std::string appended_;
};

/// Every material and set name must be one .veg token; element sets must not use the
/// prefix of the reader's material sets.
void checkVegNames(const TetMesh& mesh) {
  for (const Material& m : mesh.materials()) checkVegName(m.name, "material");
  for (const auto& [name, members] : mesh.elementSets()) {
    checkVegName(name, "element set");
    if (name.rfind(kMaterialSetPrefix, 0) == 0) {
      throw ValidationError("writeVeg: element set name '" + name + "' uses the reserved prefix " +
                            std::string(kMaterialSetPrefix));
    }
  }
  for (const auto& [name, members] : mesh.vertexSets()) checkVegName(name, "vertex set");
}

/// The *VERTICES and *ELEMENTS sections (1-based ids).
void writeVegGeometry(std::ostream& out, const TetMesh& mesh) {
  out << "*VERTICES\n" << mesh.numVertices() << " 3 0 0\n";
  for (int v = 0; v < mesh.numVertices(); ++v) {
    const Eigen::Vector3d x = mesh.restPosition(v);
    out << v + 1 << ' ' << detail::formatDouble(x.x()) << ' ' << detail::formatDouble(x.y()) << ' '
        << detail::formatDouble(x.z()) << '\n';
  }
  const int corners = mesh.verticesPerElement();
  out << "\n*ELEMENTS\n"
      << (mesh.isHexahedral() ? "CUBIC" : "TET") << '\n'
      << mesh.numElements() << ' ' << corners << " 0\n";
  const auto connectivity = mesh.connectivity();
  for (int e = 0; e < mesh.numElements(); ++e) {
    out << e + 1;
    for (int a = 0; a < corners; ++a) out << ' ' << connectivity(a, e) + 1;
    out << '\n';
  }
}

/// One *MATERIAL section per material.
void writeVegMaterials(std::ostream& out, const TetMesh& mesh) {
  for (const Material& m : mesh.materials()) {
    out << "\n*MATERIAL " << m.name << '\n';
    if (m.mooneyRivlin) {
      // E and nu are not written: the reader derives them from mu01, mu10, v1.
      out << "MOONEYRIVLIN, " << detail::formatDouble(m.density) << ", " << detail::formatDouble(m.mooneyRivlin->mu01)
          << ", " << detail::formatDouble(m.mooneyRivlin->mu10) << ", " << detail::formatDouble(m.mooneyRivlin->v1)
          << '\n';
    } else {
      out << "ENU, " << detail::formatDouble(m.density) << ", " << detail::formatDouble(m.youngsModulus) << ", "
          << detail::formatDouble(m.poissonRatio) << '\n';
    }
  }
}

/// One *REGION line per material that has elements, naming an existing set with exactly
/// those elements when there is one, otherwise a helper set (written here).
void writeVegRegions(std::ostringstream& out, const TetMesh& mesh) {
  std::vector<std::vector<int>> materialElements(mesh.materials().size());
  for (int e = 0; e < mesh.numElements(); ++e)
    materialElements[static_cast<std::size_t>(mesh.elementMaterialIndex(e))].push_back(e);
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
}

/// The <PointData> (displacement, pointArrays) and <CellData> (material, cellArrays) sections.
void appendVtuData(VtuBuilder& vtu, const TetMesh& mesh, const Eigen::VectorXd& displacement,
                   const std::vector<VtuArray>& pointArrays, const std::vector<VtuArray>& cellArrays) {
  const auto numVertices = static_cast<std::size_t>(mesh.numVertices());
  const auto numElements = static_cast<std::size_t>(mesh.numElements());
  vtu.xml() << "      <PointData" << (displacement.size() != 0 ? " Vectors=\"displacement\"" : "") << ">\n";
  if (displacement.size() != 0) vtu.array("Float64", "displacement", 3, displacement.data(), 3 * numVertices);
  for (const VtuArray& array : pointArrays) {
    vtu.array("Float64", array.name, array.components, array.values.data(), array.values.size());
  }
  vtu.xml() << "      </PointData>\n      <CellData>\n";
  const std::vector<int>& materials = mesh.elementMaterials();
  vtu.array("Int32", "material", 1, materials.data(), numElements);
  for (const VtuArray& array : cellArrays) {
    vtu.array("Float64", array.name, array.components, array.values.data(), array.values.size());
  }
  vtu.xml() << "      </CellData>\n";
}

/// The <Cells> arrays of the elements: connectivity, offsets and VTK types
/// (VTK_TETRA 10, VTK_HEXAHEDRON 12, whose vertex order the mesh's hexahedra use).
void appendVtuCells(VtuBuilder& vtu, const TetMesh& mesh) {
  const auto numElements = static_cast<std::size_t>(mesh.numElements());
  const auto corners = static_cast<std::size_t>(mesh.verticesPerElement());
  const auto elements = mesh.connectivity();
  std::vector<std::int32_t> connectivity(elements.data(), elements.data() + corners * numElements);
  std::vector<std::int32_t> offsets(numElements);
  for (std::size_t e = 0; e < numElements; ++e) offsets[e] = static_cast<std::int32_t>(corners * (e + 1));
  constexpr std::uint8_t vtkTetra = 10;
  constexpr std::uint8_t vtkHexahedron = 12;
  const std::vector<std::uint8_t> types(numElements, mesh.isHexahedral() ? vtkHexahedron : vtkTetra);
  vtu.array("Int32", "connectivity", 1, connectivity.data(), connectivity.size());
  vtu.array("Int32", "offsets", 1, offsets.data(), offsets.size());
  vtu.array("UInt8", "types", 1, types.data(), types.size());
}

}  // namespace

void writeVeg(const std::filesystem::path& path, const TetMesh& mesh) {
  checkVegNames(mesh);
  std::ostringstream out;
  out << "# " << mesh.numVertices() << " vertices, " << mesh.numElements() << " "
      << elementKindPlural(mesh.elementKind()) << ", " << mesh.materials().size() << " materials\n";
  writeVegGeometry(out, mesh);
  writeVegMaterials(out, mesh);
  for (const auto& [name, members] : mesh.elementSets()) {
    out << "\n*SET " << name << '\n';
    writeIdList(out, members);
  }
  for (const auto& [name, members] : mesh.vertexSets()) {
    out << "\n*VERTEXSET " << name << '\n';
    writeIdList(out, members);
  }
  writeVegRegions(out, mesh);
  writeAtomically(path, out.str());
}

void writeVtu(const std::filesystem::path& path, const TetMesh& mesh, const Eigen::VectorXd& displacement,
              const std::vector<VtuArray>& pointArrays, const std::vector<VtuArray>& cellArrays, VtuEncoding encoding) {
  if (displacement.size() != 0 && displacement.size() != mesh.numDofs()) {
    throw ValidationError("writeVtu: displacement has " + std::to_string(displacement.size()) +
                          " entries, expected 0 or " + std::to_string(mesh.numDofs()));
  }
  for (const VtuArray& array : pointArrays) checkArray(array, mesh.numVertices(), "point");
  for (const VtuArray& array : cellArrays) checkArray(array, mesh.numElements(), "cell");
  const auto numVertices = static_cast<std::size_t>(mesh.numVertices());
  const auto numElements = static_cast<std::size_t>(mesh.numElements());

  VtuBuilder vtu(encoding);
  vtu.xml() << "<?xml version=\"1.0\"?>\n"
            << "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\""
            << (std::endian::native == std::endian::little ? "LittleEndian" : "BigEndian")
            << "\" header_type=\"UInt64\">\n"
            << "  <UnstructuredGrid>\n"
            << "    <Piece NumberOfPoints=\"" << numVertices << "\" NumberOfCells=\"" << numElements << "\">\n";
  appendVtuData(vtu, mesh, displacement, pointArrays, cellArrays);
  // Rest positions: the displacement array carries the deformation (Warp By Vector),
  // so it must not be added here as well.
  vtu.xml() << "      <Points>\n";
  vtu.array("Float64", "", 3, mesh.restPositions().data(), 3 * numVertices);
  vtu.xml() << "      </Points>\n      <Cells>\n";
  appendVtuCells(vtu, mesh);
  vtu.xml() << "      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n";
  writeAtomically(path, vtu.finish());
}

void writePvd(const std::filesystem::path& path, const std::vector<PvdEntry>& entries) {
  std::ostringstream out;
  out << "<?xml version=\"1.0\"?>\n"
      << "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n";
  for (const PvdEntry& entry : entries) {
    out << "    <DataSet timestep=\"" << detail::formatDouble(entry.time) << "\" group=\"\" part=\"0\" file=\""
        << xmlEscape(entry.file.generic_string()) << "\"/>\n";
  }
  out << "  </Collection>\n</VTKFile>\n";
  writeAtomically(path, out.str());
}

VtuSeriesWriter::VtuSeriesWriter(std::filesystem::path folder, VtuEncoding encoding)
    : folder_(std::move(folder)), encoding_(encoding) {
  std::error_code ec;
  std::filesystem::create_directories(folder_, ec);
  if (ec) throw Error("cannot create the .vtu folder '" + folder_.string() + "': " + ec.message());
}

std::string VtuSeriesWriter::frameFileName(std::int64_t frame) {
  char name[40];
  std::snprintf(name, sizeof(name), "frame_%05lld.vtu", static_cast<long long>(frame));
  return name;
}

void VtuSeriesWriter::writeFrame(std::int64_t frame, double time, const TetMesh& mesh,
                                 const Eigen::VectorXd& displacement, const std::vector<VtuArray>& pointArrays) {
  const std::string name = frameFileName(frame);
  writeVtu(folder_ / name, mesh, displacement, pointArrays, {}, encoding_);
  entries_.push_back({time, name});
  writeCollection();
}

void VtuSeriesWriter::addExistingFrame(std::int64_t frame, double time) {
  entries_.push_back({time, frameFileName(frame)});
}

void VtuSeriesWriter::writeCollection() const { writePvd(collectionPath(), entries_); }

}  // namespace asyncfem
