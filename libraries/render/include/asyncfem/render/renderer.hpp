// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <array>
#include <asyncfem/image/image.hpp>
#include <asyncfem/render/camera.hpp>
#include <memory>
#include <optional>
#include <vector>

namespace asyncfem {

/// One triangle surface to draw in a frame. The references must stay valid during
/// OffscreenRenderer::render().
struct DrawSurface {
  const Eigen::Matrix3Xd& positions;                 ///< 3 x m vertex positions (world, mesh units)
  const std::vector<std::array<int, 3>>& triangles;  ///< 0-based vertex ids
  /// Per-vertex RGB in [0, 1] (3 x m, e.g. a region tint); empty: RenderStyle::surfaceColor.
  const Eigen::Matrix3Xf* colors = nullptr;
};

/// A square checkered floor perpendicular to the camera's up direction.
struct GroundPlane {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  ///< a point of the plane (its centre)
  double halfSize = 1.0;                             ///< half the side length
  double tileSize = 0.1;                             ///< side of one checker tile
  bool shadow = true;                                ///< darken the floor under the surfaces (projection along -up)
};

/// The ground under box for a scene whose up direction is up (non-zero): perpendicular to
/// up, 2% of the box diagonal below the box's lowest corner along up, centred under the
/// box's centre, 4 diagonals to each side, tiles of 1, 2 or 5 times a power of ten near a
/// sixth of the diagonal, with a shadow.
GroundPlane groundBelow(const BoundingBox& box, const Eigen::Vector3d& up);
/// The ground {x : up.normalized() . x = height} (a scene's contact ground), centred under
/// box's centre and sized and tiled as groundBelow's.
GroundPlane groundAt(const BoundingBox& box, const Eigen::Vector3d& up, double height);

/// How a frame looks. Colours are RGB in [0, 1].
struct RenderStyle {
  Eigen::Vector3f background = Eigen::Vector3f(1.0F, 1.0F, 1.0F);
  Eigen::Vector3f surfaceColor = Eigen::Vector3f(0.62F, 0.68F, 0.78F);
  /// Vertex normals average the faces around a vertex whose normal is within this angle
  /// of the face being shaded, so smooth parts shade smoothly and edges (the corners of a
  /// box) stay sharp.
  double creaseAngleDegrees = 40.0;
  std::optional<GroundPlane> ground;
  /// The two checker colours of the ground.
  std::array<Eigen::Vector3f, 2> groundColors = {Eigen::Vector3f(0.86F, 0.86F, 0.84F),
                                                 Eigen::Vector3f(0.76F, 0.76F, 0.74F)};
};

/// Off-screen rasteriser: an OSMesa (Mesa's software OpenGL) context and its colour
/// buffer, owned for the renderer's lifetime; no display and no GPU needed. Shading is
/// per pixel (a small GLSL 1.20 program): two directional lights fixed to the camera
/// (key from upper left, fill from the right), a sky/ground ambient term and a weak
/// specular highlight, both triangle sides lit.
///
/// Deterministic: the same input gives the same bytes (Mesa's rasteriser has no random
/// state; its threads split the image into fixed tiles). One renderer must be used by one
/// thread at a time; distinct renderers may run on distinct threads. OSMesa and GL types
/// stay inside the implementation.
class OffscreenRenderer {
 public:
  /// Images of width x height pixels (each in [1, 4096]). supersampling s in [1, 4]
  /// renders s*width x s*height and averages s x s blocks (antialiasing). Throws
  /// asyncfem::Error when the sizes are out of range or OSMesa cannot create a context.
  OffscreenRenderer(int width, int height, int supersampling = 2);
  ~OffscreenRenderer();
  OffscreenRenderer(OffscreenRenderer&&) noexcept;
  OffscreenRenderer& operator=(OffscreenRenderer&&) noexcept;
  OffscreenRenderer(const OffscreenRenderer&) = delete;
  OffscreenRenderer& operator=(const OffscreenRenderer&) = delete;

  int width() const;
  int height() const;
  int supersampling() const;

  /// Draws the surfaces (and the ground, if style has one) seen by camera. Per-corner
  /// normals are recomputed from the positions at every call. Throws asyncfem::Error for
  /// a triangle naming a vertex out of range, colours of the wrong size, or a GL failure.
  Image render(const std::vector<DrawSurface>& surfaces, const Camera& camera, const RenderStyle& style);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace asyncfem
