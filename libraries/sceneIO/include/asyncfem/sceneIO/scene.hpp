// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <asyncfem/contact/penaltyContact.hpp>
#include <asyncfem/hyperelasticFEM/hyperelasticOptions.hpp>
#include <asyncfem/problem/problem.hpp>
#include <asyncfem/stiffnessMatrix/assembler.hpp>
#include <asyncfem/volumetricMesh/generators.hpp>
#include <asyncfem/volumetricMesh/vertexSelection.hpp>
#include <asyncfem/volumetricMesh/writers.hpp>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace asyncfem {

/// A scene as written in its JSON file (format: docs/scene-format.md), checked for types,
/// ranges and unknown keys but not yet against the mesh (set names, vertex ids: that is
/// buildSimulation's job). Plain data: utilities may change fields (command-line
/// overrides) before building. Paths are already resolved against the scene's folder.
struct Scene {
  /// Where the mesh comes from.
  enum class MeshSource { file, beam, box };
  struct Mesh {
    MeshSource source = MeshSource::file;
    std::filesystem::path file;  ///< MeshSource::file: .veg, .node/.ele or .msh
    BeamSpec beam;               ///< MeshSource::beam: makeBeamMesh parameters
    BoxMeshSpec box;             ///< MeshSource::box: makeBoxMesh parameters
  };

  /// New material constants for the elements of an element set; fields left empty keep
  /// the value of the material the elements had.
  struct MaterialOverride {
    std::string set;
    std::optional<double> density;
    std::optional<double> youngsModulus;
    std::optional<double> poissonRatio;
  };

  /// Axis-aligned box [min, max] (inclusive) selecting the vertices whose rest position
  /// lies in it.
  using Box = VertexBox;

  /// Fixed vertices: the union of vertex sets, boxes and a Vega .bou file (1-based ids).
  struct Fixed {
    std::vector<std::string> sets;
    std::vector<Box> boxes;
    std::optional<std::filesystem::path> bouFile;
  };

  enum class ForceType {
    pull,     ///< constant total force, split evenly over the vertices, during a window
    impulse,  ///< total impulse (force x time), split evenly, delivered within one step
  };
  /// One external load, on a vertex set or on an explicit list of (0-based) vertex ids.
  struct Force {
    ForceType type = ForceType::pull;
    std::string set;                                   ///< vertex set name, or empty when vertices are listed
    std::vector<int> vertices;                         ///< 0-based vertex ids (when set is empty)
    Eigen::Vector3d vector = Eigen::Vector3d::Zero();  ///< pull: total force; impulse: total impulse
    double start = 0.0;                                ///< pull: active for start <= t < end
    double end = std::numeric_limits<double>::infinity();
    double time = 0.0;  ///< impulse: when it is delivered
  };

  /// linear and corotational FEM, and the hyperelastic materials of library hyperelasticFEM:
  /// the problem layer's own types, so that a scene's choice passes to ProblemSettings as is.
  using ForceModelKind = ForceModelType;
  using Tangent = TangentKind;

  /// Name of the scene for messages: the file name as given to loadScene, or the
  /// sourceName given to parseScene. Every error reads "<sourceName>: <key path>: ...".
  std::string sourceName = "scene";
  /// Folder relative paths were resolved against.
  std::filesystem::path baseDirectory;
  std::string description;

  Mesh mesh;
  std::vector<MaterialOverride> materials;
  Fixed fixed;
  Eigen::Vector3d gravity = Eigen::Vector3d::Zero();  ///< acceleration, length / time^2
  std::vector<Force> forces;
  MassType mass = MassType::consistent;
  double rayleighAlpha = 0.0;  ///< D = alpha M + beta K
  double rayleighBeta = 0.0;
  ForceModelKind forceModel = ForceModelKind::linear;
  /// Penalty contact with static obstacles (docs/scene-format.md, "contact").
  struct Contact {
    std::vector<ContactPlane> planes;  ///< the ground is one of them
    std::vector<ContactSphere> spheres;
    PenaltyContactParameters parameters;
    bool enabled() const { return !planes.empty() || !spheres.empty(); }
  } contact;
  Tangent tangent = Tangent::simple;  ///< corotational only
  /// Hyperelastic kinds only: inversion threshold, compression resistance, SPD tangent,
  /// StVK formulation, Mooney-Rivlin parameters (docs/scene-format.md, "forceModel").
  HyperelasticOptions hyperelastic;

  struct IntegratorSettings {
    std::string name = "backward-euler";
    /// h (> 0). With stepsPerFrame it is set from it: (1 / frames.rate) / stepsPerFrame.
    double timestep = 0.0;
    /// Steps per frame given instead of the timestep (integrator.stepsPerFrame); 0: the
    /// timestep was given, and must divide the frame interval (resolveFrameTiming).
    int stepsPerFrame = 0;
    /// Integrator-specific keys, passed through unparsed to the integrator's factory
    /// (see IntegratorRegistry), which rejects keys it does not know.
    nlohmann::json options = nlohmann::json::object();
  } integrator;

  struct FrameSettings {
    double rate = 30.0;  ///< frames per time unit; frame interval = 1 / rate
    int count = 60;
  } frames;

  struct OutputSettings {
    std::filesystem::path file;       ///< .afsim output; empty: none given in the scene
    std::filesystem::path vtuFolder;  ///< empty: no .vtu files
    int vtuEvery = 1;                 ///< write a .vtu every this many frames
    bool velocities = false;          ///< also store velocities in the .afsim file
    bool sync = false;                ///< fsync after every frame
    /// output.vtu.encoding: how the .vtu files store their arrays
    VtuEncoding vtuEncoding = VtuEncoding::binary;
  } output;
};

/// How the integrator's steps fill the frames of a scene.
struct FrameTiming {
  double frameInterval = 0.0;  ///< 1 / frames.rate
  double timestep = 0.0;       ///< h
  int stepsPerFrame = 0;       ///< frameInterval / h, a whole number
};

/// The relative distance |h - frameInterval / N| / (frameInterval / N) up to which a
/// timestep counts as the divisor frameInterval / N of the frame interval: far above the
/// round-off of a timestep written as 1/990 or with ten significant digits
/// (0.001010101010), far below the gap 1/N between neighbouring divisors (N <= 1e9).
inline constexpr double timestepDivisorTolerance = 1e-9;

/// The frame timing of a scene: with integrator.stepsPerFrame N, h = frameInterval / N;
/// otherwise N = frameInterval / integrator.timestep, which must be a whole number to
/// timestepDivisorTolerance (h is then used as given). Throws asyncfem::ValidationError
/// "<scene>: integrator.timestep: ..." naming the frame interval and the two nearest valid
/// timesteps with their steps per frame when it is not, and "<scene>: frames: ..." for a
/// bad frames.rate.
FrameTiming resolveFrameTiming(const Scene& scene);

/// Reads and parses a scene file. Relative paths in it resolve against its folder.
/// Throws asyncfem::ParseError "FILE:LINE: invalid JSON ..." for malformed JSON, and
/// asyncfem::ValidationError "FILE: key.path: message" for unknown keys, wrong types and
/// bad values; asyncfem::Error if the file cannot be read.
Scene loadScene(const std::filesystem::path& path);

/// Parses a scene from JSON. basePath: folder relative paths resolve against;
/// sourceName: what error messages call the scene.
Scene parseScene(const nlohmann::json& json, const std::filesystem::path& basePath,
                 const std::string& sourceName = "scene");

/// Throws asyncfem::ValidationError "<scene.sourceName>: <keyPath>: <message>", the form
/// of every scene error (for integrator factories reading their own options).
[[noreturn]] void throwSceneError(const Scene& scene, const std::string& keyPath, const std::string& message);

}  // namespace asyncfem
