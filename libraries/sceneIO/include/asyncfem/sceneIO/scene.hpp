// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <asyncfem/collision/broadPhase.hpp>
#include <asyncfem/contact/meshObstacle.hpp>
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

/// How the integrator's steps fill the frames of a scene, resolved once from frames.rate,
/// frames.count and integrator.timestep or integrator.stepsPerFrame (resolveFrameTiming).
/// Scene::timing holds the one copy of these values; everything downstream reads them
/// there (or in Simulation::timing, built from it), never the scene keys they came from.
struct FrameTiming {
  double frameRate = 0.0;      ///< frames per second (frames.rate)
  double frameInterval = 0.0;  ///< 1 / frameRate, seconds
  /// frameInterval / timestep, a whole number >= 1; 0 while unresolved (see Scene::timing)
  int stepsPerFrame = 0;
  double timestep = 0.0;  ///< h, seconds
  int frameCount = 0;     ///< frames to run (frames.count)
  /// Whether the timestep divides the frame interval (stepsPerFrame >= 1).
  bool resolved() const { return stepsPerFrame > 0; }
  bool operator==(const FrameTiming&) const = default;
};

/// The timing keys of a scene file as written: the input of resolveFrameTiming, read by
/// parseScene and not kept (Scene::timing is what a scene holds).
struct TimingKeys {
  double frameRate = 30.0;  ///< frames.rate, frames per second
  int frameCount = 60;      ///< frames.count
  double timestep = 0.0;    ///< integrator.timestep, seconds; read when stepsPerFrame is 0
  int stepsPerFrame = 0;    ///< integrator.stepsPerFrame; 0: the timestep is given instead
};

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

  /// A rigid placement of an object or obstacle: x -> translation + rotation (scale x).
  struct Placement {
    Eigen::Vector3d translation = Eigen::Vector3d::Zero();
    Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();  ///< {"axis": [x, y, z], "angle": degrees}
    double scale = 1.0;                                            ///< uniform, > 0
    Eigen::Vector3d apply(const Eigen::Vector3d& x) const { return translation + rotation * (scale * x); }
  };

  /// One body of a scene of several (objects, docs/scene-format.md): its mesh is placed,
  /// and the bodies are simulated as one mesh of disconnected parts, in which the object's
  /// name is a vertex set and an element set, and its own sets are "<name>/<set>".
  struct Object {
    std::string name;
    Mesh mesh;
    /// The object's fixed vertices: its own sets, boxes in its mesh's coordinates (before
    /// the placement), a .bou file of its ids; in the scene's mesh the vertex set
    /// "<name>/fixed", which parseScene adds to fixed.sets.
    Fixed fixed;
    Placement placement;
    Eigen::Vector3d velocity = Eigen::Vector3d::Zero();  ///< initial velocity (length / time)
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

  Mesh mesh;  ///< unused when objects is not empty
  /// Several bodies (objects) instead of mesh; empty: the scene's one body is mesh.
  std::vector<Object> objects;
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
    std::vector<ContactPlane> planes;    ///< the ground is one of them
    std::optional<ContactPlane> ground;  ///< contact.ground when given (also in planes), for renderers
    std::vector<ContactSphere> spheres;
    /// A triangle-mesh obstacle (contact.obstacles[i]): a surface file read with assimp,
    /// placed, and moved along path when it has keys.
    struct Obstacle {
      std::string name;
      std::filesystem::path file;
      bool closed = true;  ///< must be a closed, consistently oriented surface (inside known)
      Placement placement;
      std::vector<RigidKey> path;  ///< empty: static; else at least two keys
    };
    std::vector<Obstacle> obstacles;
    /// contact.surfaces: contact between the bodies' boundary surfaces and the obstacles
    /// (SurfaceContact); on when given or when there are obstacles.
    struct Surfaces {
      std::optional<double> thickness;  ///< dhat; default 0.2 x the mean boundary edge length
      bool betweenBodies = true;
      bool self = false;
      bool edges = true;
      BroadPhaseMethod broadPhase = kDefaultBroadPhase;
    };
    std::optional<Surfaces> surfaces;
    PenaltyContactParameters parameters;
    bool implicit = false;  ///< contact.implicit: linearized in the step (single-rate backward Euler)
    bool enabled() const { return !planes.empty() || !spheres.empty() || surfaces.has_value(); }
  } contact;
  Tangent tangent = Tangent::simple;  ///< corotational only
  /// Hyperelastic kinds only: inversion threshold, compression resistance, SPD tangent,
  /// StVK formulation, Mooney-Rivlin parameters (docs/scene-format.md, "forceModel").
  HyperelasticOptions hyperelastic;

  struct IntegratorSettings {
    std::string name = "backward-euler";
    /// Integrator-specific keys, passed through unparsed to the integrator's factory
    /// (see IntegratorRegistry), which rejects keys it does not know.
    nlohmann::json options = nlohmann::json::object();
  } integrator;

  /// The frame timing: frames.rate, frames.count and integrator.timestep or
  /// integrator.stepsPerFrame resolved by parseScene, the one owner of the timestep, the
  /// steps per frame and the frame count (the keys themselves are not kept). Change it
  /// with overrideFrameTiming only, which resolves it again; read it for a run with
  /// requireFrameTiming. When the written timestep does not divide the frame interval the
  /// scene is still read (tools that only need its mesh use it) and timing holds the rate,
  /// count and timestep as written with stepsPerFrame 0 (not resolved()).
  FrameTiming timing;

  struct OutputSettings {
    std::filesystem::path file;       ///< .afsim output; empty: none given in the scene
    std::filesystem::path vtuFolder;  ///< empty: no .vtu files
    int vtuEvery = 1;                 ///< write a .vtu every this many frames
    bool velocities = false;          ///< also store velocities in the .afsim file
    /// output.contactForces: also store every vertex's contact force in the .afsim file
    /// (and the .vtu files), evaluated at each frame's state (contactForces())
    bool contactForces = false;
    bool sync = false;  ///< fsync after every frame
    /// output.regions: each .afsim record also carries every vertex's step ratio (the fast
    /// regions in use at that frame); unset: on exactly for run-time regions
    /// (recordsRegionRatios()).
    std::optional<bool> regions;
    /// output.vtu.encoding: how the .vtu files store their arrays
    VtuEncoding vtuEncoding = VtuEncoding::binary;
  } output;
};

/// The relative distance |h - frameInterval / N| / (frameInterval / N) up to which a
/// timestep counts as the divisor frameInterval / N of the frame interval: far above the
/// round-off of a timestep written as 1/990 or with ten significant digits
/// (0.001010101010), far below the gap 1/N between neighbouring divisors (N <= 1e9).
inline constexpr double timestepDivisorTolerance = 1e-9;

/// The frame timing of timing keys: with stepsPerFrame N, h = frameInterval / N; otherwise
/// N = frameInterval / timestep, which must be a whole number to timestepDivisorTolerance
/// (h is then used as given). Throws asyncfem::ValidationError "<sourceName>: frames.rate:
/// ..." for a rate that is not > 0, "<sourceName>: frames.count: ..." for a count below 1,
/// and "<sourceName>: integrator.timestep: ..." for a timestep that is not > 0 or that does
/// not divide the frame interval, naming the frame interval and the two nearest valid
/// timesteps with their steps per frame.
FrameTiming resolveFrameTiming(const TimingKeys& keys, const std::string& sourceName);

/// scene.timing, for a run: throws the asyncfem::ValidationError of resolveFrameTiming
/// (naming integrator.timestep) when it is not resolved().
const FrameTiming& requireFrameTiming(const Scene& scene);

/// Timing values given outside the scene file (a utility's --dt, --steps-per-frame,
/// --frames, a benchmark's configuration); an empty field keeps the scene's.
struct TimingOverrides {
  // (Initialized members: designated initializers may leave any of them out.)
  std::optional<double> timestep{};    ///< replaces integrator.timestep or integrator.stepsPerFrame
  std::optional<int> stepsPerFrame{};  ///< replaces integrator.timestep or integrator.stepsPerFrame
  std::optional<int> frameCount{};     ///< replaces frames.count
  /// replaces frames.rate; the timestep (not the steps per frame) stays unless given
  std::optional<double> frameRate{};
};

/// The one way to change a scene's timing: applies overrides to scene.timing and resolves
/// it again (resolveFrameTiming), with its errors named by the scene key each override
/// replaces; scene is unchanged when it throws. Giving both timestep and stepsPerFrame is
/// a ValidationError.
void overrideFrameTiming(Scene& scene, const TimingOverrides& overrides);

/// Whether the scene's integrator options ask for run-time regions
/// (integrator.options.regions = {"adaptive": ...}).
bool hasRunTimeRegions(const Scene& scene);
/// Whether a run of the scene records region ratios in its .afsim records: output.regions
/// when given, else hasRunTimeRegions().
bool recordsRegionRatios(const Scene& scene);

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
