// SPDX-License-Identifier: BSD-3-Clause
// OSMesa + legacy-profile OpenGL with a GLSL 1.20 program; all GL stays in this file.
#define GL_GLEXT_PROTOTYPES 1
#include <GL/gl.h>
#include <GL/glext.h>
#include <GL/osmesa.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/render/renderer.hpp>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <utility>

#if defined(ASYNCFEM_SANITIZE)
// LeakSanitizer: Mesa's OSMesa keeps per-context and per-thread state that
// OSMesaDestroyContext does not free (every context made here is destroyed). Only leaks
// whose stacks lie inside Mesa are suppressed; one with a frame in AsyncFEM still fails.
extern "C" const char* __lsan_default_suppressions() {  // NOLINT(bugprone-reserved-identifier)
  return "leak:libOSMesa.so\nleak:libgallium\nleak:libglapi.so\n";
}
#endif

namespace asyncfem {

namespace {

struct ContextDeleter {
  void operator()(osmesa_context* context) const { OSMesaDestroyContext(context); }
};
using ContextHandle = std::unique_ptr<osmesa_context, ContextDeleter>;

// Eye-space lighting: a key light from the upper left and front, a fill light from the
// right, a sky/ground ambient term (by the eye-space normal's y) and a weak highlight.
constexpr const char* vertexShaderSource = R"(#version 120
varying vec3 eyePosition;
varying vec3 eyeNormal;
varying vec3 vertexColor;
void main() {
  vec4 p = gl_ModelViewMatrix * gl_Vertex;
  eyePosition = p.xyz;
  eyeNormal = gl_NormalMatrix * gl_Normal;
  vertexColor = gl_Color.rgb;
  gl_Position = gl_ProjectionMatrix * p;
}
)";

constexpr const char* fragmentShaderSource = R"(#version 120
varying vec3 eyePosition;
varying vec3 eyeNormal;
varying vec3 vertexColor;
uniform int flatShading;
uniform vec4 flatColor;
void main() {
  if (flatShading == 1) {
    gl_FragColor = flatColor;
    return;
  }
  vec3 n = normalize(eyeNormal);
  if (!gl_FrontFacing) {
    n = -n;
  }
  vec3 toEye = normalize(-eyePosition);
  vec3 key = normalize(vec3(-0.45, 0.75, 0.55));
  vec3 fill = normalize(vec3(0.8, 0.05, 0.35));
  float keyDiffuse = max(dot(n, key), 0.0);
  float fillDiffuse = max(dot(n, fill), 0.0);
  vec3 ambient = mix(vec3(0.20, 0.19, 0.18), vec3(0.32, 0.34, 0.38), 0.5 + 0.5 * n.y);
  vec3 halfway = normalize(key + toEye);
  float highlight = keyDiffuse > 0.0 ? 0.18 * pow(max(dot(n, halfway), 0.0), 48.0) : 0.0;
  vec3 color = vertexColor * (ambient + 0.72 * keyDiffuse + 0.28 * fillDiffuse) + vec3(highlight);
  gl_FragColor = vec4(clamp(color, 0.0, 1.0), 1.0);
}
)";

GLuint compileShader(GLenum type, const char* source) {
  const GLuint shader = glCreateShader(type);
  glShaderSource(shader, 1, &source, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (ok == 0) {
    char log[2048] = {0};
    glGetShaderInfoLog(shader, sizeof(log) - 1, nullptr, log);
    throw Error(std::string("OffscreenRenderer: shader compilation failed: ") + log);
  }
  return shader;
}

/// Interleaved-by-array vertex data of one draw call (one entry per triangle corner).
struct CornerArrays {
  std::vector<float> positions;
  std::vector<float> normals;
  std::vector<float> colors;
  void clear() {
    positions.clear();
    normals.clear();
    colors.clear();
  }
  void add(const Eigen::Vector3d& p, const Eigen::Vector3d& n, const Eigen::Vector3f& c) {
    positions.insert(positions.end(),
                     {static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z())});
    normals.insert(normals.end(), {static_cast<float>(n.x()), static_cast<float>(n.y()), static_cast<float>(n.z())});
    colors.insert(colors.end(), {c.x(), c.y(), c.z()});
  }
  GLsizei count() const { return static_cast<GLsizei>(positions.size() / 3); }
};

/// The triangles around each vertex of a surface, in compressed rows: those around vertex
/// v are incident[offsets[v]] .. incident[offsets[v + 1] - 1], in increasing order.
struct VertexTriangles {
  std::vector<int> offsets;
  std::vector<int> incident;
};

/// Checks that every triangle names a vertex in [0, m) and lists the triangles around
/// each vertex.
VertexTriangles vertexTriangles(const std::vector<std::array<int, 3>>& triangles, Eigen::Index m) {
  VertexTriangles around;
  around.offsets.assign(static_cast<std::size_t>(m) + 1, 0);
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    for (const int v : triangles[t]) {
      if (v < 0 || v >= m) {
        throw Error("OffscreenRenderer: triangle " + std::to_string(t) + " names vertex " + std::to_string(v) +
                    ", out of range [0, " + std::to_string(m) + ")");
      }
      ++around.offsets[static_cast<std::size_t>(v) + 1];
    }
  }
  for (std::size_t v = 1; v < around.offsets.size(); ++v) {
    around.offsets[v] += around.offsets[v - 1];
  }
  std::vector<int> cursor(around.offsets.begin(), around.offsets.end() - 1);
  around.incident.resize(static_cast<std::size_t>(around.offsets.back()));
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    for (const int v : triangles[t]) {
      around.incident[static_cast<std::size_t>(cursor[static_cast<std::size_t>(v)]++)] = static_cast<int>(t);
    }
  }
  return around;
}

/// Per-corner normals: the corner of triangle t at vertex v gets the area-weighted sum of
/// the normals of the triangles around v that are within the crease angle of t.
void appendSurface(const DrawSurface& surface, const Eigen::Vector3f& defaultColor, double creaseAngleDegrees,
                   CornerArrays& out) {
  const Eigen::Index m = surface.positions.cols();
  if (surface.colors != nullptr && surface.colors->cols() != m) {
    throw Error("OffscreenRenderer: " + std::to_string(surface.colors->cols()) + " colours for " + std::to_string(m) +
                " vertices");
  }
  const VertexTriangles around = vertexTriangles(surface.triangles, m);
  const std::size_t numTriangles = surface.triangles.size();
  std::vector<Eigen::Vector3d> areaNormals(numTriangles);
  std::vector<Eigen::Vector3d> unitNormals(numTriangles);
  for (std::size_t t = 0; t < numTriangles; ++t) {
    const auto& tri = surface.triangles[t];
    const Eigen::Vector3d a = surface.positions.col(tri[0]);
    areaNormals[t] = (surface.positions.col(tri[1]) - a).cross(surface.positions.col(tri[2]) - a);
    const double length = areaNormals[t].norm();
    unitNormals[t] = length > 0.0 ? Eigen::Vector3d(areaNormals[t] / length) : Eigen::Vector3d::Zero();
  }
  const double cosCrease = std::cos(creaseAngleDegrees * std::numbers::pi / 180.0);
  out.positions.reserve(out.positions.size() + (9 * numTriangles));
  out.normals.reserve(out.normals.size() + (9 * numTriangles));
  out.colors.reserve(out.colors.size() + (9 * numTriangles));
  for (std::size_t t = 0; t < numTriangles; ++t) {
    for (const int v : surface.triangles[t]) {
      Eigen::Vector3d normal = Eigen::Vector3d::Zero();
      for (int s = around.offsets[static_cast<std::size_t>(v)]; s < around.offsets[static_cast<std::size_t>(v) + 1];
           ++s) {
        const auto f = static_cast<std::size_t>(around.incident[static_cast<std::size_t>(s)]);
        if (unitNormals[f].dot(unitNormals[t]) >= cosCrease) {
          normal += areaNormals[f];
        }
      }
      const double length = normal.norm();
      normal = length > 0.0 ? Eigen::Vector3d(normal / length) : unitNormals[t];
      const Eigen::Vector3f color = surface.colors != nullptr ? Eigen::Vector3f(surface.colors->col(v)) : defaultColor;
      out.add(surface.positions.col(v), normal, color);
    }
  }
}

/// Appends the ground's checker tiles as pairs of triangles in the plane through its
/// centre normal to up (unit); returns the four corners of the plane.
std::array<Eigen::Vector3d, 4> appendGround(const GroundPlane& g, const Eigen::Vector3d& up,
                                            const std::array<Eigen::Vector3f, 2>& colors, CornerArrays& out) {
  const Eigen::Vector3d u = up.unitOrthogonal();
  const Eigen::Vector3d w = up.cross(u);
  const int tiles = std::clamp(static_cast<int>(std::ceil(2.0 * g.halfSize / g.tileSize)), 1, 400);
  const double tile = 2.0 * g.halfSize / tiles;
  const Eigen::Vector3d origin = g.center - (g.halfSize * u) - (g.halfSize * w);
  for (int i = 0; i < tiles; ++i) {
    for (int j = 0; j < tiles; ++j) {
      const Eigen::Vector3f& color = colors[static_cast<std::size_t>((i + j) % 2)];
      const Eigen::Vector3d p00 = origin + (i * tile * u) + (j * tile * w);
      const Eigen::Vector3d p10 = p00 + (tile * u);
      const Eigen::Vector3d p01 = p00 + (tile * w);
      const Eigen::Vector3d p11 = p10 + (tile * w);
      for (const Eigen::Vector3d& p : {p00, p10, p11, p00, p11, p01}) {
        out.add(p, up, color);
      }
    }
  }
  return {origin, origin + (2.0 * g.halfSize * u), origin + (2.0 * g.halfSize * w),
          origin + (2.0 * g.halfSize * (u + w))};
}

/// Near and far distances that bracket every surface vertex and, when given, the ground's
/// corners (so depth precision follows the scene).
std::pair<double, double> depthRange(const Eigen::Matrix4d& view, const std::vector<DrawSurface>& surfaces,
                                     const std::array<Eigen::Vector3d, 4>* groundCorners) {
  double nearest = std::numeric_limits<double>::infinity();
  double farthest = 0.0;
  const auto extendDepth = [&](const Eigen::Vector3d& p) {
    const double depth = -(view.block<1, 3>(2, 0).dot(p) + view(2, 3));
    nearest = std::min(nearest, depth);
    farthest = std::max(farthest, depth);
  };
  for (const DrawSurface& surface : surfaces) {
    for (Eigen::Index k = 0; k < surface.positions.cols(); ++k) {
      extendDepth(surface.positions.col(k));
    }
  }
  if (groundCorners != nullptr) {
    for (const Eigen::Vector3d& p : *groundCorners) {
      extendDepth(p);
    }
  }
  if (!(farthest > 0.0)) {
    farthest = 1.0;
  }
  const double farDistance = farthest * 1.05;
  const double nearDistance = std::max(nearest * 0.95, farDistance * 1e-4);
  return {nearDistance, farDistance};
}

/// Box-filters s x s blocks of the RGBA buffer ((s width) x (s height), top row first)
/// into a width x height RGB image.
Image downsample(const std::vector<GLubyte>& buffer, int width, int height, int s) {
  Image image;
  image.width = width;
  image.height = height;
  image.pixels.resize(3 * static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  const auto rowBytes = static_cast<std::size_t>(4 * width * s);
  const int samples = s * s;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      int sum[3] = {0, 0, 0};
      for (int dy = 0; dy < s; ++dy) {
        const GLubyte* row = buffer.data() + (static_cast<std::size_t>((y * s) + dy) * rowBytes);
        for (int dx = 0; dx < s; ++dx) {
          const GLubyte* p = row + (4 * static_cast<std::size_t>((x * s) + dx));
          sum[0] += p[0];
          sum[1] += p[1];
          sum[2] += p[2];
        }
      }
      std::uint8_t* out = image.pixel(x, y);
      for (int c = 0; c < 3; ++c) {
        out[c] = static_cast<std::uint8_t>((sum[c] + (samples / 2)) / samples);
      }
    }
  }
  return image;
}

void drawCorners(const CornerArrays& arrays) {
  if (arrays.count() == 0) {
    return;
  }
  glVertexPointer(3, GL_FLOAT, 0, arrays.positions.data());
  glNormalPointer(GL_FLOAT, 0, arrays.normals.data());
  glColorPointer(3, GL_FLOAT, 0, arrays.colors.data());
  glDrawArrays(GL_TRIANGLES, 0, arrays.count());
}

}  // namespace

struct OffscreenRenderer::Impl {
  int width = 0;
  int height = 0;
  int supersampling = 1;
  ContextHandle context;
  std::vector<GLubyte> buffer;  // RGBA, (s width) x (s height), top row first
  GLuint program = 0;
  GLint flatShadingLocation = -1;
  GLint flatColorLocation = -1;
  CornerArrays surfaces;
  CornerArrays ground;

  int bufferWidth() const { return width * supersampling; }
  int bufferHeight() const { return height * supersampling; }

  void makeCurrent() {
    if (OSMesaMakeCurrent(context.get(), buffer.data(), GL_UNSIGNED_BYTE, bufferWidth(), bufferHeight()) == 0) {
      throw Error("OffscreenRenderer: OSMesaMakeCurrent failed");
    }
    OSMesaPixelStore(OSMESA_Y_UP, 0);  // row 0 of the buffer is the top of the image
    if (program != 0) {
      return;
    }
    const GLuint vertexShader = compileShader(GL_VERTEX_SHADER, vertexShaderSource);
    const GLuint fragmentShader = compileShader(GL_FRAGMENT_SHADER, fragmentShaderSource);
    program = glCreateProgram();
    glAttachShader(program, vertexShader);
    glAttachShader(program, fragmentShader);
    glLinkProgram(program);
    GLint ok = 0;
    glGetProgramiv(program, GL_LINK_STATUS, &ok);
    if (ok == 0) {
      char log[2048] = {0};
      glGetProgramInfoLog(program, sizeof(log) - 1, nullptr, log);
      throw Error(std::string("OffscreenRenderer: shader link failed: ") + log);
    }
    flatShadingLocation = glGetUniformLocation(program, "flatShading");
    flatColorLocation = glGetUniformLocation(program, "flatColor");
  }

  /// Makes the context current and clears it; sets the matrices, the depth test, the
  /// shading program and the vertex arrays every frame uses.
  void beginFrame(const Eigen::Vector3f& background, const Eigen::Matrix4d& projection, const Eigen::Matrix4d& view) {
    makeCurrent();
    glViewport(0, 0, bufferWidth(), bufferHeight());
    glClearColor(background.x(), background.y(), background.z(), 1.0F);
    glClearStencil(0);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT | GL_STENCIL_BUFFER_BIT);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDisable(GL_CULL_FACE);
    glMatrixMode(GL_PROJECTION);
    glLoadMatrixd(projection.data());
    glMatrixMode(GL_MODELVIEW);
    glLoadMatrixd(view.data());
    glUseProgram(program);
    glUniform1i(flatShadingLocation, 0);
    glEnableClientState(GL_VERTEX_ARRAY);
    glEnableClientState(GL_NORMAL_ARRAY);
    glEnableClientState(GL_COLOR_ARRAY);
  }

  /// Draws the ground and, if it has one, the surfaces' shadow on it. The ground marks its
  /// pixels in the stencil buffer (1) so that the shadow darkens each ground pixel once (2)
  /// and nothing else.
  void drawGround(const GroundPlane& plane, const Eigen::Vector3d& up, const Eigen::Matrix4d& view) {
    glEnable(GL_STENCIL_TEST);
    glStencilFunc(GL_ALWAYS, 1, 0xFF);
    glStencilOp(GL_KEEP, GL_KEEP, GL_REPLACE);
    drawCorners(ground);
    if (plane.shadow && surfaces.count() > 0) {
      // Flatten the surfaces onto the plane n.x = d along n: x' = x - (n.x - d) n.
      const double d = up.dot(plane.center);
      Eigen::Matrix4d flatten = Eigen::Matrix4d::Identity();
      flatten.block<3, 3>(0, 0) -= up * up.transpose();
      flatten.block<3, 1>(0, 3) = d * up;
      const Eigen::Matrix4d shadowView = view * flatten;
      glLoadMatrixd(shadowView.data());
      glStencilFunc(GL_EQUAL, 1, 0xFF);
      glStencilOp(GL_KEEP, GL_KEEP, GL_INCR);
      glEnable(GL_BLEND);
      glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
      glEnable(GL_POLYGON_OFFSET_FILL);
      glPolygonOffset(-1.0F, -1.0F);
      glUniform1i(flatShadingLocation, 1);
      glUniform4f(flatColorLocation, 0.15F, 0.15F, 0.17F, 0.35F);
      drawCorners(surfaces);
      glUniform1i(flatShadingLocation, 0);
      glDisable(GL_POLYGON_OFFSET_FILL);
      glDisable(GL_BLEND);
      glLoadMatrixd(view.data());
    }
    glDisable(GL_STENCIL_TEST);
  }
};

OffscreenRenderer::OffscreenRenderer(int width, int height, int supersampling) : impl_(std::make_unique<Impl>()) {
  if (width < 1 || height < 1 || width > 4096 || height > 4096) {
    throw Error("OffscreenRenderer: image size " + std::to_string(width) + " x " + std::to_string(height) +
                " out of range [1, 4096]");
  }
  if (supersampling < 1 || supersampling > 4) {
    throw Error("OffscreenRenderer: supersampling " + std::to_string(supersampling) + " out of range [1, 4]");
  }
  impl_->width = width;
  impl_->height = height;
  impl_->supersampling = supersampling;
  // RGBA colour, 24-bit depth, 8-bit stencil (ground shadows), no accumulation buffer.
  impl_->context.reset(OSMesaCreateContextExt(OSMESA_RGBA, 24, 8, 0, nullptr));
  if (!impl_->context) {
    throw Error("OffscreenRenderer: OSMesaCreateContextExt failed (is Mesa's libOSMesa installed?)");
  }
  impl_->buffer.resize(4 * static_cast<std::size_t>(impl_->bufferWidth()) *
                       static_cast<std::size_t>(impl_->bufferHeight()));
}

OffscreenRenderer::~OffscreenRenderer() = default;
OffscreenRenderer::OffscreenRenderer(OffscreenRenderer&&) noexcept = default;
OffscreenRenderer& OffscreenRenderer::operator=(OffscreenRenderer&&) noexcept = default;

int OffscreenRenderer::width() const { return impl_->width; }
int OffscreenRenderer::height() const { return impl_->height; }
int OffscreenRenderer::supersampling() const { return impl_->supersampling; }

Image OffscreenRenderer::render(const std::vector<DrawSurface>& surfaces, const Camera& camera,
                                const RenderStyle& style) {
  Impl& impl = *impl_;
  impl.surfaces.clear();
  for (const DrawSurface& surface : surfaces) {
    appendSurface(surface, style.surfaceColor, style.creaseAngleDegrees, impl.surfaces);
  }
  const Eigen::Vector3d up = camera.up.normalized();
  impl.ground.clear();
  std::array<Eigen::Vector3d, 4> groundCorners;
  if (style.ground) {
    groundCorners = appendGround(*style.ground, up, style.groundColors, impl.ground);
  }
  const Eigen::Matrix4d view = viewMatrix(camera);
  const auto [nearDistance, farDistance] = depthRange(view, surfaces, style.ground ? &groundCorners : nullptr);
  const Eigen::Matrix4d projection =
      projectionMatrix(camera, static_cast<double>(impl.width) / impl.height, nearDistance, farDistance);

  impl.beginFrame(style.background, projection, view);
  if (style.ground) {
    impl.drawGround(*style.ground, up, view);
  }
  drawCorners(impl.surfaces);
  glFinish();
  const GLenum glError = glGetError();
  if (glError != GL_NO_ERROR) {
    throw Error("OffscreenRenderer: OpenGL error " + std::to_string(glError));
  }
  return downsample(impl.buffer, impl.width, impl.height, impl.supersampling);
}

}  // namespace asyncfem
