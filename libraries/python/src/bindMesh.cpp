// SPDX-License-Identifier: BSD-3-Clause
// libraries/volumetricMesh: TetMesh, materials, sets, readers, writers, generators, queries.

#include <pybind11/operators.h>

#include <asyncfem/volumetricMesh/generators.hpp>
#include <asyncfem/volumetricMesh/queries.hpp>
#include <asyncfem/volumetricMesh/readers.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <asyncfem/volumetricMesh/writers.hpp>
#include <bindings.hpp>

namespace asyncfem::python {

namespace {

using Release = py::call_guard<py::gil_scoped_release>;

TetMesh makeMesh(const py::handle& positions, const py::handle& elements, std::vector<Material> materials,
                 const py::handle& elementMaterials) {
  const auto points = matrixArgument(positions, "positions", -1, 3);
  // (m, 8) rows are hexahedra in Vega's CUBIC order; anything else must be (m, 4) tetrahedra.
  const py::array given = py::module_::import("numpy").attr("asarray")(elements);
  const bool hexahedral = given.ndim() == 2 && given.shape(1) == 8;
  if (given.ndim() == 2 && given.shape(1) != 4 && !hexahedral) {
    throw py::value_error(
        "elements: expected an integer array of shape (m, 4) (tetrahedra) or (m, 8) (hexahedra), "
        "got " +
        std::to_string(given.shape(1)) + " vertices per row");
  }
  const auto tets = indexMatrixArgument(elements, "elements", -1, hexahedral ? 8 : 4);
  std::vector<int> materialIndices;
  if (elementMaterials.is_none()) {
    materialIndices.assign(static_cast<std::size_t>(tets.shape(0)), 0);
  } else {
    materialIndices = indexListArgument(elementMaterials, "element_materials");
  }
  if (static_cast<py::ssize_t>(materialIndices.size()) != tets.shape(0)) {
    throw py::value_error("element_materials: expected " + std::to_string(tets.shape(0)) +
                          " entries (one per element), got " + std::to_string(materialIndices.size()));
  }
  // (n, 3) C order is the 3 x n column-major layout TetMesh stores.
  Eigen::Matrix3Xd rest = Eigen::Map<const Eigen::Matrix3Xd>(points.data(), 3, points.shape(0));
  if (hexahedral) {
    HexElements connectivity = Eigen::Map<const HexElements>(tets.data(), 8, tets.shape(0));
    return {std::move(rest), std::move(connectivity), std::move(materials), std::move(materialIndices)};
  }
  Eigen::Matrix4Xi connectivity = Eigen::Map<const Eigen::Matrix4Xi>(tets.data(), 4, tets.shape(0));
  return {std::move(rest), std::move(connectivity), std::move(materials), std::move(materialIndices)};
}

py::dict setsDict(const std::map<std::string, std::vector<int>>& sets) {
  py::dict result;
  for (const auto& [name, members] : sets) result[py::str(name)] = intArray(members);
  return result;
}

void checkVertex(const TetMesh& mesh, int vertex) { checkIndex(vertex, mesh.numVertices(), "vertex"); }
void checkElement(const TetMesh& mesh, int element) { checkIndex(element, mesh.numElements(), "element"); }

VtuArray vtuArray(const std::string& name, const py::handle& value, int count, const char* what) {
  const std::string label = std::string(what) + "[" + name + "]";
  py::array array = py::module_::import("numpy").attr("asarray")(value);
  VtuArray result;
  result.name = name;
  if (array.ndim() == 2) {
    const auto checked = matrixArgument(value, label.c_str(), count, 3);
    result.components = 3;
    result.values.assign(checked.data(), checked.data() + checked.size());
  } else {
    const auto checked = vectorArgument(value, label.c_str(), count);
    result.values.assign(checked.data(), checked.data() + checked.size());
  }
  return result;
}

std::vector<VtuArray> vtuArrays(const py::dict& arrays, int count, const char* what) {
  std::vector<VtuArray> result;
  for (const auto& [key, value] : arrays) {
    result.push_back(vtuArray(py::str(key).cast<std::string>(), value, count, what));
  }
  return result;
}

void bindMaterialsAndSets(py::class_<TetMesh>& mesh);

/// Material and TetMesh.
void bindMeshClasses(py::module_& module) {
  py::class_<Material>(module, "Material", "Isotropic linear-elastic material (SI units by convention).")
      .def(py::init([](std::string name, double density, double youngsModulus, double poissonRatio) {
             return Material{std::move(name), density, youngsModulus, poissonRatio};
           }),
           py::arg("name") = "default", py::arg("density") = 1000.0, py::arg("youngs_modulus") = 1e6,
           py::arg("poisson_ratio") = 0.45)
      .def_readwrite("name", &Material::name)
      .def_readwrite("density", &Material::density, "rho (kg/m^3)")
      .def_readwrite("youngs_modulus", &Material::youngsModulus, "E (Pa)")
      .def_readwrite("poisson_ratio", &Material::poissonRatio, "nu, in (-1, 0.5)")
      .def(py::self == py::self)  // NOLINT(misc-redundant-expression)
      .def("__repr__", [](const Material& m) {
        return "Material(name='" + m.name + "', density=" + py::repr(py::float_(m.density)).cast<std::string>() +
               ", youngs_modulus=" + py::repr(py::float_(m.youngsModulus)).cast<std::string>() +
               ", poisson_ratio=" + py::repr(py::float_(m.poissonRatio)).cast<std::string>() + ")";
      });

  py::class_<TetMesh> mesh(
      module, "TetMesh",
      "Volumetric mesh of linear tetrahedra or trilinear hexahedra (one kind per mesh), with a material "
      "per element and named vertex and element sets.");
  mesh.def(py::init(&makeMesh), py::arg("positions"), py::arg("elements"),
           py::arg("materials") = std::vector<Material>{Material{}}, py::arg("element_materials") = py::none(),
           "positions: (n, 3) float64 rest positions; elements: (m, 4) integer vertex ids of tetrahedra, or (m, 8) of "
           "hexahedra in Vega's CUBIC order (bottom face counter-clockwise seen from above, then the top face); "
           "materials: list of "
           "Material; element_materials: m indices into materials (default: all 0).")
      .def_property_readonly("num_vertices", &TetMesh::numVertices)
      .def_property_readonly("num_elements", &TetMesh::numElements)
      .def_property_readonly("num_dofs", &TetMesh::numDofs, "3 * num_vertices")
      .def_property_readonly(
          "rest_positions",
          [](py::object self) { return transposedView(self.cast<const TetMesh&>().restPositions(), self); },
          "(n, 3) read-only view of the rest positions (no copy)")
      .def_property_readonly(
          "elements", [](py::object self) { return transposedView(self.cast<const TetMesh&>().elements(), self); },
          "(m, 4) read-only int32 view of the connectivity (no copy); a hexahedral mesh raises "
          "ValidationError (see hexahedra)")
      .def_property_readonly(
          "element_kind", [](const TetMesh& mesh) { return mesh.isHexahedral() ? "hexahedron" : "tetrahedron"; },
          "\"tetrahedron\" or \"hexahedron\" (Vega CUBIC and Gmsh hexahedra): one kind per mesh")
      .def_property_readonly(
          "hexahedra", [](py::object self) { return transposedView(self.cast<const TetMesh&>().hexahedra(), self); },
          "(m, 8) read-only int32 view of a hexahedral mesh's connectivity (no copy; vertex order of Vega's "
          "CUBIC elements); a tetrahedral mesh raises ValidationError")
      .def(
          "rest_position",
          [](const TetMesh& mesh, int v) {
            checkVertex(mesh, v);
            return Eigen::Vector3d(mesh.restPosition(v));
          },
          py::arg("vertex"), "rest position of a vertex (3,)")
      .def(
          "element",
          [](const TetMesh& mesh, int e) {
            checkElement(mesh, e);
            return Eigen::Vector4i(mesh.element(e));
          },
          py::arg("element"), "the four vertex ids of an element")
      .def(
          "element_rest_positions",
          [](const TetMesh& mesh, int e) {
            checkElement(mesh, e);
            return Eigen::Matrix<double, 3, 4>(mesh.elementRestPositions(e));
          },
          py::arg("element"), "3 x 4: the rest positions of the element's vertices as columns");
  bindMaterialsAndSets(mesh);
}

/// TetMesh's materials, vertex and element sets.
void bindMaterialsAndSets(py::class_<TetMesh>& mesh) {
  mesh.def_property_readonly("materials", &TetMesh::materials)
      .def_property_readonly("element_materials", [](const TetMesh& mesh) { return intArray(mesh.elementMaterials()); })
      .def(
          "element_material",
          [](const TetMesh& mesh, int e) {
            checkElement(mesh, e);
            return mesh.elementMaterial(e);
          },
          py::arg("element"), "the Material of an element")
      .def("find_material", &TetMesh::findMaterial, py::arg("name"), "index of the material, or -1")
      .def("add_material", &TetMesh::addMaterial, py::arg("material"),
           "adds (or replaces the one with the same name) and returns its index")
      .def("assign_material", &TetMesh::assignMaterial, py::arg("element_set"), py::arg("material_index"),
           "gives the elements of a set the material at material_index")
      .def_property_readonly("element_sets", [](const TetMesh& mesh) { return setsDict(mesh.elementSets()); })
      .def_property_readonly("vertex_sets", [](const TetMesh& mesh) { return setsDict(mesh.vertexSets()); })
      .def(
          "element_set", [](const TetMesh& mesh, const std::string& name) { return intArray(mesh.elementSet(name)); },
          py::arg("name"), "element ids of a named element set")
      .def(
          "vertex_set", [](const TetMesh& mesh, const std::string& name) { return intArray(mesh.vertexSet(name)); },
          py::arg("name"), "vertex ids of a named vertex set")
      .def(
          "set_vertices", [](const TetMesh& mesh, const std::string& name) { return intArray(mesh.setVertices(name)); },
          py::arg("name"), "the vertex set called name, else the vertices of the element set called name")
      .def(
          "set_element_set",
          [](TetMesh& mesh, const std::string& name, const py::handle& members) {
            mesh.setElementSet(name, indexListArgument(members, "elements"));
          },
          py::arg("name"), py::arg("elements"), "creates or replaces an element set")
      .def(
          "set_vertex_set",
          [](TetMesh& mesh, const std::string& name, const py::handle& members) {
            mesh.setVertexSet(name, indexListArgument(members, "vertices"));
          },
          py::arg("name"), py::arg("vertices"), "creates or replaces a vertex set")
      .def(
          "set_element",
          [](TetMesh& mesh, int e, const Eigen::Vector4i& vertices) {
            checkElement(mesh, e);
            mesh.setElement(e, vertices);
          },
          py::arg("element"), py::arg("vertices"), "replaces the four vertex ids of an element")
      .def("__repr__", [](const TetMesh& mesh) {
        return "TetMesh(" + std::to_string(mesh.numVertices()) + " vertices, " + std::to_string(mesh.numElements()) +
               " elements, " + std::to_string(mesh.materials().size()) + " materials)";
      });

  // Readers.
}

void bindMeshWriters(py::module_& module);

/// Readers, writers and their options and reports.
void bindMeshFiles(py::module_& module) {
  py::class_<MeshReadOptions>(
      module, "MeshReadOptions",
      "Options of the mesh readers: default material, reorientation of inverted elements, degenerate volume tolerance")
      .def(py::init([](std::optional<Material> defaultMaterial, bool reorient, double tolerance) {
             return MeshReadOptions{std::move(defaultMaterial), reorient, tolerance};
           }),
           py::arg("default_material") = py::none(), py::arg("reorient_inverted_elements") = true,
           py::arg("degenerate_volume_tolerance") = 1e-12)
      .def_readwrite("default_material", &MeshReadOptions::defaultMaterial)
      .def_readwrite("reorient_inverted_elements", &MeshReadOptions::reorientInvertedElements)
      .def_readwrite("degenerate_volume_tolerance", &MeshReadOptions::degenerateVolumeTolerance);
  py::class_<MeshReadReport>(
      module, "MeshReadReport",
      "What a mesh reader noticed: format, warnings, reoriented elements, unused vertices, ignored elements")
      .def(py::init<>())
      .def_readonly("format", &MeshReadReport::format)
      .def_readonly("warnings", &MeshReadReport::warnings)
      .def_readonly("reoriented_elements", &MeshReadReport::reorientedElements)
      .def_readonly("unused_vertices", &MeshReadReport::unusedVertices)
      .def_readonly("ignored_elements", &MeshReadReport::ignoredElements);
  using Reader = TetMesh (*)(const std::filesystem::path&, const MeshReadOptions&, MeshReadReport*);
  const auto addReader = [&module](const char* name, Reader reader, const char* doc) {
    module.def(
        name,
        [reader](const std::filesystem::path& path, const MeshReadOptions& options, bool withReport) -> py::object {
          MeshReadReport report;
          TetMesh mesh;
          {
            py::gil_scoped_release release;
            mesh = reader(path, options, &report);
          }
          if (withReport) return py::make_tuple(std::move(mesh), std::move(report));
          return py::cast(std::move(mesh));
        },
        py::arg("path"), py::arg("options") = MeshReadOptions{}, py::arg("with_report") = false, doc);
  };
  addReader("read_mesh", &readMesh,
            "Reads .veg, TetGen .node/.ele (or their base name) or Gmsh .msh 2.2/4.1 by extension. With "
            "with_report=True returns (mesh, MeshReadReport). ParseError names the file and line.");
  addReader("read_veg", &readVeg, "Reads a Vega .veg file.");
  addReader("read_tetgen", &readTetGen, "Reads a TetGen .node/.ele pair.");
  addReader("read_gmsh", &readGmsh, "Reads a Gmsh .msh (ASCII 2.2 or 4.1) file.");
  bindMeshWriters(module);
}

/// .bou reading, .veg and .vtu writing, .vtu series.
void bindMeshWriters(py::module_& module) {
  module.def(
      "read_bou",
      [](const std::filesystem::path& path, int numVertices) { return intArray(readBou(path, numVertices)); },
      py::arg("path"), py::arg("num_vertices"), "Vega .bou: sorted unique 0-based vertex ids");

  // Writers.
  py::enum_<VtuEncoding>(module, "VtuEncoding", ".vtu data encoding: binary (raw appended) or ascii")
      .value("binary", VtuEncoding::binary)
      .value("ascii", VtuEncoding::ascii);
  module.def("write_veg", &writeVeg, py::arg("path"), py::arg("mesh"), Release(),
             "Vega .veg that read_veg reads back exactly");
  module.def(
      "write_vtu",
      [](const std::filesystem::path& path, const TetMesh& mesh, const py::object& displacement,
         const py::dict& pointArrays, const py::dict& cellArrays, VtuEncoding encoding) {
        const Eigen::VectorXd u =
            displacement.is_none() ? Eigen::VectorXd() : toVector(displacement, "displacement", mesh.numDofs());
        const auto points = vtuArrays(pointArrays, mesh.numVertices(), "point_arrays");
        const auto cells = vtuArrays(cellArrays, mesh.numElements(), "cell_arrays");
        py::gil_scoped_release release;
        writeVtu(path, mesh, u, points, cells, encoding);
      },
      py::arg("path"), py::arg("mesh"), py::arg("displacement") = py::none(), py::arg("point_arrays") = py::dict(),
      py::arg("cell_arrays") = py::dict(), py::arg("encoding") = VtuEncoding::binary,
      "VTK XML .vtu at the rest positions with point array 'displacement' (3n) and the given arrays: "
      "name -> (n,) or (n, 3) per point, (m,) or (m, 3) per cell.");
  module.def(
      "write_pvd",
      [](const std::filesystem::path& path, const std::vector<std::pair<double, std::filesystem::path>>& entries) {
        std::vector<PvdEntry> list;
        for (const auto& [time, file] : entries) list.push_back(PvdEntry{time, file});
        writePvd(path, list);
      },
      py::arg("path"), py::arg("entries"), "ParaView collection from a list of (time, file)");
  py::class_<VtuSeriesWriter>(module, "VtuSeriesWriter",
                              "FOLDER/frame_NNNNN.vtu per frame and FOLDER/frames.pvd, rewritten after each frame")
      .def(py::init<std::filesystem::path, VtuEncoding>(), py::arg("folder"), py::arg("encoding") = VtuEncoding::binary)
      .def(
          "write_frame",
          [](VtuSeriesWriter& writer, std::int64_t frame, double time, const TetMesh& mesh,
             const py::handle& displacement) {
            const Eigen::VectorXd u = toVector(displacement, "displacement", mesh.numDofs());
            py::gil_scoped_release release;
            writer.writeFrame(frame, time, mesh, u);
          },
          py::arg("frame"), py::arg("time"), py::arg("mesh"), py::arg("displacement"),
          "writes FOLDER/frame_NNNNN.vtu (rest positions and the displacement array) and rewrites frames.pvd")
      .def("add_existing_frame", &VtuSeriesWriter::addExistingFrame, py::arg("frame"), py::arg("time"),
           "lists a frame already on disk in frames.pvd (for resumed runs)")
      .def("write_collection", &VtuSeriesWriter::writeCollection,
           "writes the .pvd collection of the frames written so far")
      .def_property_readonly("folder", &VtuSeriesWriter::folder)
      .def_property_readonly("collection_path", &VtuSeriesWriter::collectionPath)
      .def_static("frame_file_name", &VtuSeriesWriter::frameFileName, py::arg("frame"),
                  "the file name of frame k (frame_NNNNN.vtu)");

  // Generators.
}

/// The mesh generators and their settings.
void bindMeshGenerators(py::module_& module) {
  py::class_<BoxRegion>(module, "BoxRegion", "A box of a generated mesh whose elements get their own material and set")
      .def(py::init([](std::string name, const Eigen::Vector3d& min, const Eigen::Vector3d& max, Material material) {
             return BoxRegion{std::move(name), min, max, std::move(material)};
           }),
           py::arg("name"), py::arg("min"), py::arg("max"), py::arg("material"))
      .def_readwrite("name", &BoxRegion::name)
      .def_readwrite("min", &BoxRegion::min)
      .def_readwrite("max", &BoxRegion::max)
      .def_readwrite("material", &BoxRegion::material);
  py::class_<BoxMeshSpec>(module, "BoxMeshSpec", "Settings of make_box_mesh: origin, size, cells, material, regions")
      .def(py::init<>())
      .def_readwrite("origin", &BoxMeshSpec::origin)
      .def_readwrite("size", &BoxMeshSpec::size)
      .def_readwrite("cells", &BoxMeshSpec::cells)
      .def_readwrite("material", &BoxMeshSpec::material)
      .def_readwrite("regions", &BoxMeshSpec::regions);
  module.def("make_box_mesh", &makeBoxMesh, py::arg("spec"), Release(),
             "box cut into cubes of six tets; vertex sets xmin..zmax, plus the regions' sets");
  py::class_<BeamSpec>(module, "BeamSpec",
                       "Settings of make_beam_mesh: the default scene's cantilever with a stiff tip")
      .def(py::init<>())
      .def_readwrite("length", &BeamSpec::length)
      .def_readwrite("height", &BeamSpec::height)
      .def_readwrite("depth", &BeamSpec::depth)
      .def_readwrite("cells_along_length", &BeamSpec::cellsAlongLength)
      .def_readwrite("tip_fraction", &BeamSpec::tipFraction)
      .def_readwrite("body", &BeamSpec::body)
      .def_readwrite("tip", &BeamSpec::tip);
  module.def("make_beam_mesh", &makeBeamMesh, py::arg("spec") = BeamSpec{}, Release(),
             "cantilever along +x: sets 'root' (x = 0), 'tip' (stiff, light last tip_fraction)");
  py::class_<CellBlock>(module, "CellBlock",
                        "A block of lattice cells [begin, end) with a material and a set name (make_cell_mesh)")
      .def(py::init([](std::string name, const Eigen::Vector3i& begin, const Eigen::Vector3i& end, Material material) {
             return CellBlock{std::move(name), begin, end, std::move(material)};
           }),
           py::arg("name"), py::arg("begin"), py::arg("end"), py::arg("material"))
      .def_readwrite("name", &CellBlock::name)
      .def_readwrite("begin", &CellBlock::begin)
      .def_readwrite("end", &CellBlock::end)
      .def_readwrite("material", &CellBlock::material);
  py::class_<CellVertexRing>(module, "CellVertexRing",
                             "A vertex set of rings of vertices around element sets (make_cell_mesh)")
      .def(py::init([](std::string name, std::vector<std::string> around, int rings) {
             return CellVertexRing{std::move(name), std::move(around), rings};
           }),
           py::arg("name"), py::arg("around"), py::arg("rings") = 1)
      .def_readwrite("name", &CellVertexRing::name)
      .def_readwrite("around", &CellVertexRing::around)
      .def_readwrite("rings", &CellVertexRing::rings);
  py::class_<CellMeshSpec>(module, "CellMeshSpec",
                           "Settings of make_cell_mesh: cell size, origin, blocks, vertex rings")
      .def(py::init<>())
      .def_readwrite("origin", &CellMeshSpec::origin)
      .def_readwrite("cell_size", &CellMeshSpec::cellSize)
      .def_readwrite("blocks", &CellMeshSpec::blocks)
      .def_readwrite("vertex_rings", &CellMeshSpec::vertexRings);
  module.def("make_cell_mesh", &makeCellMesh, py::arg("spec"), Release(), "union of lattice cells, conforming");
  py::class_<AntennaSpec>(module, "AntennaSpec", "Settings of make_antenna_mesh: a light rod on a heavy block")
      .def(py::init<>())
      .def_readwrite("cell_size", &AntennaSpec::cellSize)
      .def_readwrite("block_cells", &AntennaSpec::blockCells)
      .def_readwrite("rod_cells", &AntennaSpec::rodCells)
      .def_readwrite("block", &AntennaSpec::block)
      .def_readwrite("rod", &AntennaSpec::rod);
  module.def("make_antenna_mesh", &makeAntennaMesh, py::arg("spec") = AntennaSpec{}, Release(),
             "the antenna mesh (models/antenna): a light, soft rod on a heavy block");
  py::class_<SnailSpec>(module, "SnailSpec", "Settings of make_snail_mesh: a heavy shell with light eye tentacles")
      .def(py::init<>())
      .def_readwrite("cell_size", &SnailSpec::cellSize)
      .def_readwrite("tentacle_cells", &SnailSpec::tentacleCells)
      .def_readwrite("body", &SnailSpec::body)
      .def_readwrite("shell", &SnailSpec::shell)
      .def_readwrite("tentacles", &SnailSpec::tentacles);
  module.def("make_snail_mesh", &makeSnailMesh, py::arg("spec") = SnailSpec{}, Release(),
             "the snail mesh (models/snail): a heavy shell with light eye tentacles");

  // Queries.
}

/// Queries of a mesh: volumes, masses, boundary, bounding box, quality.
void bindMeshQueries(py::module_& module) {
  module.def(
      "signed_element_volume",
      [](const TetMesh& mesh, int e) {
        checkElement(mesh, e);
        return signedElementVolume(mesh, e);
      },
      py::arg("mesh"), py::arg("element"), "signed volume of an element (negative when inverted)");
  module.def("element_volumes", &elementVolumes, py::arg("mesh"), Release(), "|V| per element");
  module.def("total_volume", &totalVolume, py::arg("mesh"), Release(), "total volume of the mesh");
  module.def("total_mass", &totalMass, py::arg("mesh"), Release(), "total mass of the mesh (densities times volumes)");
  module.def(
      "boundary_triangles",
      [](const TetMesh& mesh) {
        std::vector<std::array<int, 3>> triangles;
        {
          py::gil_scoped_release release;
          triangles = boundaryTriangles(mesh);
        }
        return triangleArray(triangles);
      },
      py::arg("mesh"), "(k, 3) int32, outward oriented");
  module.def(
      "vertex_element_adjacency",
      [](const TetMesh& mesh) {
        const VertexElementAdjacency adjacency = vertexElementAdjacency(mesh);
        return py::make_tuple(intArray(adjacency.offsets), intArray(adjacency.elements));
      },
      py::arg("mesh"), "(offsets, elements): the elements of vertex v are elements[offsets[v]:offsets[v+1]]");
  py::class_<BoundingBox>(module, "BoundingBox", "An axis-aligned box (min, max corners)")
      .def(py::init([](const Eigen::Vector3d& min, const Eigen::Vector3d& max) {
             return BoundingBox{min, max};
           }),
           py::arg("min"), py::arg("max"))
      .def_readwrite("min", &BoundingBox::min)
      .def_readwrite("max", &BoundingBox::max);
  module.def(
      "bounding_box",
      [](const TetMesh& mesh, const py::object& displacement) {
        return boundingBox(
            mesh, displacement.is_none() ? Eigen::VectorXd() : toVector(displacement, "displacement", mesh.numDofs()));
      },
      py::arg("mesh"), py::arg("displacement") = py::none(), "the axis-aligned bounding box of the rest positions");
  py::class_<ElementQuality>(module, "ElementQuality",
                             "Quality of one element: smallest and largest dihedral angle, aspect ratio")
      .def_readonly("min_dihedral_angle", &ElementQuality::minDihedralAngle, "radians")
      .def_readonly("max_dihedral_angle", &ElementQuality::maxDihedralAngle, "radians")
      .def_readonly("aspect_ratio", &ElementQuality::aspectRatio, "1 for the regular tetrahedron");
  module.def(
      "element_quality",
      [](const TetMesh& mesh, int e) {
        checkElement(mesh, e);
        return elementQuality(mesh, e);
      },
      py::arg("mesh"), py::arg("element"), "dihedral angles and aspect ratio of one element");
  module.def(
      "element_qualities",
      [](const TetMesh& mesh) {
        const std::vector<ElementQuality> qualities = elementQualities(mesh);
        py::array_t<double> minAngle(static_cast<py::ssize_t>(qualities.size()));
        py::array_t<double> maxAngle(static_cast<py::ssize_t>(qualities.size()));
        py::array_t<double> aspect(static_cast<py::ssize_t>(qualities.size()));
        for (std::size_t i = 0; i < qualities.size(); ++i) {
          minAngle.mutable_data()[i] = qualities[i].minDihedralAngle;
          maxAngle.mutable_data()[i] = qualities[i].maxDihedralAngle;
          aspect.mutable_data()[i] = qualities[i].aspectRatio;
        }
        py::dict result;
        result["min_dihedral_angle"] = minAngle;
        result["max_dihedral_angle"] = maxAngle;
        result["aspect_ratio"] = aspect;
        return result;
      },
      py::arg("mesh"), "dict of per-element arrays: min_dihedral_angle, max_dihedral_angle, aspect_ratio");
  module.def(
      "unused_vertices", [](const TetMesh& mesh) { return intArray(unusedVertices(mesh)); }, py::arg("mesh"),
      "ids of the vertices no element uses");
}

}  // namespace

void bindMesh(py::module_& module) {
  bindMeshClasses(module);
  bindMeshFiles(module);
  bindMeshGenerators(module);
  bindMeshQueries(module);
}

}  // namespace asyncfem::python
