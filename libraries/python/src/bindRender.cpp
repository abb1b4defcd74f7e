// SPDX-License-Identifier: BSD-3-Clause
// libraries/render (built with ASYNCFEM_WITH_RENDER): off-screen frames as NumPy
// (height, width, 3) uint8 arrays, PNG in and out.

#include <asyncfem/image/image.hpp>
#include <asyncfem/image/png.hpp>
#include <asyncfem/render/camera.hpp>
#include <asyncfem/render/renderer.hpp>
#include <asyncfem/volumetricMesh/queries.hpp>
#include <bindings.hpp>

namespace asyncfem::python {

namespace {

// The image's pixels handed to NumPy without a copy: the vector moves into a capsule that
// the array owns.
py::array_t<std::uint8_t> imageArray(Image&& image) {
  auto* pixels = new std::vector<std::uint8_t>(std::move(image.pixels));  // NOLINT(cppcoreguidelines-owning-memory)
  py::capsule owner(pixels, [](void* data) { delete static_cast<std::vector<std::uint8_t>*>(data); });
  const auto width = static_cast<py::ssize_t>(image.width);
  return py::array_t<std::uint8_t>({static_cast<py::ssize_t>(image.height), width, py::ssize_t{3}},
                                   {3 * width, py::ssize_t{3}, py::ssize_t{1}}, pixels->data(), owner);
}

Image imageFromArray(const py::handle& value, const char* name) {
  const py::array array = py::module_::import("numpy").attr("asarray")(value);
  if (!array.dtype().is(py::dtype::of<std::uint8_t>()) || array.ndim() != 3 || array.shape(2) != 3) {
    throw py::value_error(std::string(name) + ": expected a uint8 array of shape (height, width, 3), got dtype " +
                          py::str(array.dtype()).cast<std::string>() + " with " + std::to_string(array.ndim()) +
                          " dimensions");
  }
  const auto contiguous = py::array_t<std::uint8_t, py::array::c_style>::ensure(array);
  Image image;
  image.height = static_cast<int>(array.shape(0));
  image.width = static_cast<int>(array.shape(1));
  image.pixels.assign(contiguous.data(), contiguous.data() + contiguous.size());
  return image;
}

/// A triangle surface given from Python, stored the way DrawSurface refers to it.
struct Surface {
  Eigen::Matrix3Xd positions;
  std::vector<std::array<int, 3>> triangles;
  Eigen::Matrix3Xf colors;
};

Surface makeSurface(const py::handle& positions, const py::handle& triangles, const py::handle& colors) {
  Surface surface;
  const auto points = matrixArgument(positions, "positions", -1, 3);
  surface.positions = Eigen::Map<const Eigen::Matrix3Xd>(points.data(), 3, points.shape(0));
  const auto faces = indexMatrixArgument(triangles, "triangles", -1, 3);
  surface.triangles.resize(static_cast<std::size_t>(faces.shape(0)));
  for (std::size_t t = 0; t < surface.triangles.size(); ++t) {
    for (std::size_t c = 0; c < 3; ++c) surface.triangles[t][c] = faces.data()[(3 * t) + c];
  }
  if (!colors.is_none()) {
    const auto rgb = matrixArgument(colors, "colors", points.shape(0), 3);
    surface.colors = Eigen::Map<const Eigen::Matrix3Xd>(rgb.data(), 3, rgb.shape(0)).cast<float>();
  }
  return surface;
}

py::array_t<std::uint8_t> renderSurfaces(OffscreenRenderer& renderer, const std::vector<Surface>& surfaces,
                                         const Camera& camera, const RenderStyle& style) {
  std::vector<DrawSurface> draw;
  for (const Surface& surface : surfaces) {
    draw.push_back(
        DrawSurface{surface.positions, surface.triangles, surface.colors.cols() > 0 ? &surface.colors : nullptr});
  }
  Image image;
  {
    py::gil_scoped_release release;
    image = renderer.render(draw, camera, style);
  }
  return imageArray(std::move(image));
}

}  // namespace

void bindRender(py::module_& module) {
  py::class_<Camera>(module, "Camera", "Pinhole camera (mesh units)")
      .def(py::init([](const Eigen::Vector3d& position, const Eigen::Vector3d& target, const Eigen::Vector3d& up,
                       double fov) {
             return Camera{position, target, up, fov};
           }),
           py::arg("position") = Eigen::Vector3d(0.0, 0.0, 5.0), py::arg("target") = Eigen::Vector3d::Zero(),
           py::arg("up") = Eigen::Vector3d::UnitY(), py::arg("vertical_field_of_view_degrees") = 30.0)
      .def_readwrite("position", &Camera::position)
      .def_readwrite("target", &Camera::target)
      .def_readwrite("up", &Camera::up)
      .def_readwrite("vertical_field_of_view_degrees", &Camera::verticalFieldOfViewDegrees);
  module.def("fit_camera", &fitCamera, py::arg("box"), py::arg("aspect"),
             py::arg("view_direction") = defaultViewDirection(), py::arg("up") = Eigen::Vector3d::UnitY(),
             py::arg("vertical_field_of_view_degrees") = 30.0, py::arg("margin") = 0.08,
             "camera that sees the whole box (aspect = width / height)");
  py::class_<GroundPlane>(module, "GroundPlane", "A checkered ground square under the mesh, optionally with its shadow")
      .def(py::init([](const Eigen::Vector3d& center, double halfSize, double tileSize, bool shadow) {
             return GroundPlane{center, halfSize, tileSize, shadow};
           }),
           py::arg("center") = Eigen::Vector3d::Zero(), py::arg("half_size") = 1.0, py::arg("tile_size") = 0.1,
           py::arg("shadow") = true)
      .def_readwrite("center", &GroundPlane::center)
      .def_readwrite("half_size", &GroundPlane::halfSize)
      .def_readwrite("tile_size", &GroundPlane::tileSize)
      .def_readwrite("shadow", &GroundPlane::shadow);
  py::class_<RenderStyle>(module, "RenderStyle", "Colours (RGB in [0, 1]), crease angle, optional ground")
      .def(py::init<>())
      .def_readwrite("background", &RenderStyle::background)
      .def_readwrite("surface_color", &RenderStyle::surfaceColor)
      .def_readwrite("crease_angle_degrees", &RenderStyle::creaseAngleDegrees)
      .def_readwrite("ground", &RenderStyle::ground)
      .def_readwrite("ground_colors", &RenderStyle::groundColors);
  py::class_<Surface>(module, "Surface",
                      "A triangle surface to draw: positions (m, 3), triangles (k, 3), colors (m, 3)")
      .def(py::init(&makeSurface), py::arg("positions"), py::arg("triangles"), py::arg("colors") = py::none());

  py::class_<OffscreenRenderer>(module, "OffscreenRenderer", "OSMesa off-screen renderer (no display, no GPU)")
      .def(py::init<int, int, int>(), py::arg("width"), py::arg("height"), py::arg("supersampling") = 2)
      .def_property_readonly("width", &OffscreenRenderer::width)
      .def_property_readonly("height", &OffscreenRenderer::height)
      .def_property_readonly("supersampling", &OffscreenRenderer::supersampling)
      .def("render", &renderSurfaces, py::arg("surfaces"), py::arg("camera"), py::arg("style") = RenderStyle{},
           "(height, width, 3) uint8 image of the surfaces")
      .def(
          "render_mesh",
          [](OffscreenRenderer& renderer, const TetMesh& mesh, const py::object& displacement,
             const std::optional<Camera>& camera, const RenderStyle& style, const py::object& colors) {
            Eigen::VectorXd u = displacement.is_none() ? Eigen::VectorXd::Zero(mesh.numDofs())
                                                       : toVector(displacement, "displacement", mesh.numDofs());
            Surface surface;
            surface.positions =
                mesh.restPositions() + Eigen::Map<const Eigen::Matrix3Xd>(u.data(), 3, mesh.numVertices());
            surface.triangles = boundaryTriangles(mesh);
            if (!colors.is_none()) {
              const auto rgb = matrixArgument(colors, "colors", mesh.numVertices(), 3);
              surface.colors = Eigen::Map<const Eigen::Matrix3Xd>(rgb.data(), 3, rgb.shape(0)).cast<float>();
            }
            const Camera view = camera ? *camera
                                       : fitCamera(boundingBox(mesh, u), static_cast<double>(renderer.width()) /
                                                                             static_cast<double>(renderer.height()));
            return renderSurfaces(renderer, {surface}, view, style);
          },
          py::arg("mesh"), py::arg("displacement") = py::none(), py::arg("camera") = py::none(),
          py::arg("style") = RenderStyle{}, py::arg("colors") = py::none(),
          "the mesh's boundary at rest + displacement; camera fitted to it when None");

  module.def(
      "write_png",
      [](const std::filesystem::path& path, const py::handle& image) {
        const Image copy = imageFromArray(image, "image");
        py::gil_scoped_release release;
        writePng(path, copy);
      },
      py::arg("path"), py::arg("image"), "writes a (height, width, 3) uint8 array as PNG");
  module.def(
      "read_png", [](const std::filesystem::path& path) { return imageArray(readPng(path)); }, py::arg("path"),
      "(height, width, 3) uint8 array");
}

}  // namespace asyncfem::python
