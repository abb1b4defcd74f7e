// SPDX-License-Identifier: BSD-3-Clause
// frameRenderer: draws the frames of a simulation output file (.afsim) as PNG images.
//
//   frameRenderer SIM.afsim (--mesh MESH | --scene SCENE.json) [--output DIR] [--frames start:stop:step]
//                 [--width W] [--height H] [--warp none|rotation-strain|modal] [--tint-set NAME] [--tint-regions]
//                 [--render-mesh FILE] [--ground] [--compare OTHER.afsim --labels "a,b"]
//                 [--video OUT.mp4 [--fps F]] [--contact-sheet SHEET.png [--sheet-columns N]] ...
//
// Writes DIR/frame_NNNNN.png (NNNNN = the frame's index in the file); with --video also a
// video of them encoded by ffmpeg, with --contact-sheet a grid of them labelled with their
// times. Progress on stderr,
// a summary on stdout. Errors print "frameRenderer: <message>" on stderr and exit with
// status 1 (2 for unusable command-line options). Reference: docs/rendering.md.

#include <CLI/CLI.hpp>
#include <algorithm>
#include <asyncfem/core/error.hpp>
#include <asyncfem/core/stopwatch.hpp>
#include <asyncfem/core/threading.hpp>
#include <asyncfem/image/png.hpp>
#include <asyncfem/image/text.hpp>
#include <asyncfem/render/renderer.hpp>
#include <asyncfem/render/surfaceEmbedding.hpp>
#include <asyncfem/render/surfaceMesh.hpp>
#include <asyncfem/render/vegaInterpolation.hpp>
#include <asyncfem/sceneIO/scene.hpp>
#include <asyncfem/sceneIO/simulation.hpp>
#include <asyncfem/sceneIO/vegaConfig.hpp>
#include <asyncfem/simulationIO/frameSelection.hpp>
#include <asyncfem/simulationIO/simulationFile.hpp>
#include <asyncfem/volumetricMesh/queries.hpp>
#include <asyncfem/volumetricMesh/readers.hpp>
#include <asyncfem/warping/warping.hpp>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <iostream>
#include <memory>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "commandLine.hpp"
#include "frameMedia.hpp"
#include "progress.hpp"

namespace {

namespace fs = std::filesystem;
using namespace asyncfem;

struct CommandLine {
  std::string simulation;
  std::optional<std::string> mesh;
  std::optional<std::string> scene;
  std::string output = "frames";
  std::string frames;
  int width = 640;
  int height = 480;
  std::string warp = "none";
  std::vector<std::string> tintSets;
  std::vector<float> tintColor{0.95F, 0.45F, 0.12F};
  bool tintRegions = false;
  std::vector<std::string> fixedSets;
  std::optional<std::string> renderMesh;
  std::optional<std::string> interp;
  bool ground = false;
  bool noObstacles = false;
  std::optional<std::string> compare;
  std::optional<std::string> labels;
  std::vector<double> cameraPosition;
  std::vector<double> cameraTarget;
  std::vector<double> cameraUp{0.0, 1.0, 0.0};
  std::vector<double> viewDirection;
  double fieldOfView = 30.0;
  int supersampling = 2;
  int threads = 0;
  bool progress = false;
  bool quiet = false;
  std::optional<std::string> video;
  double fps = 30.0;
  std::optional<std::string> contactSheet;
  int sheetColumns = 4;
};

Eigen::Vector3d toVector(const std::vector<double>& values) { return {values[0], values[1], values[2]}; }

// ---------------------------------------------------------------------------------------
// What every worker shares (read-only) and what each owns.

struct Run {
  std::string label;
  fs::path file;
};

struct Shared {
  std::shared_ptr<const TetMesh> mesh;
  std::vector<int> fixedVertices;
  WarpingKind warping = WarpingKind::none;
  SurfaceEmbedding surface;
  std::optional<Eigen::Matrix3Xf> colors;  // per surface vertex, when a set or fixed regions are tinted
  /// --tint-regions on files that record region ratios: the colours per tet vertex before
  /// each frame's regions are tinted (surface colour and --tint-set sets), and the tint.
  std::optional<Eigen::Matrix3Xf> regionBase;
  Eigen::Vector3f regionTint = Eigen::Vector3f::Zero();
  std::optional<std::vector<int>> fixedRegionRatios;  // the recorded scene's fixed regions, if any
  std::vector<Run> runs;                              // one, or two with --compare
  int assemblies = 0;                                 // matrices the problem assembled (none: only the mesh is needed)
  std::optional<ContactPlane> sceneGround;            // the scene's contact.ground, where --ground draws the floor
  std::vector<SurfaceMesh> obstacles;                 // the scene's contact spheres, drawn unless --no-obstacles
  std::vector<Eigen::Matrix3Xf> obstacleColors;       // one colour per obstacle vertex
  std::string scenePath;                              // the scene the mesh came from, if any
  std::string surfaceName = "tet mesh boundary";      // what the surface drawn is, for the summary
};

/// A worker's own state: readers of every run and warping objects (neither is
/// thread-safe), and, when rendering, its own OSMesa context.
struct Worker {
  std::vector<std::unique_ptr<SimulationReader>> readers;
  std::vector<std::unique_ptr<Warping>> warpings;
  SimulationFrame frame;

  explicit Worker(const Shared& shared) {
    for (const Run& run : shared.runs) {
      readers.push_back(std::make_unique<SimulationReader>(run.file));
      warpings.push_back(makeWarping(shared.warping, *shared.mesh, shared.fixedVertices));
    }
  }
  /// Surface positions of run r at frame k (-1: the rest shape).
  Eigen::Matrix3Xd surfacePositions(const Shared& shared, std::size_t r, std::int64_t k) {
    if (k < 0) {
      return shared.surface.restSurface().vertices;
    }
    readers[r]->readFrame(k, frame);
    return shared.surface.positions(warpings[r]->warp(frame.displacement));
  }
};

/// Runs job(worker, i) for i in [0, count) on `threads` threads, each with its own
/// Worker; rethrows the first exception after every thread stopped.
template <class Job>
void forEachParallel(const Shared& shared, int threads, std::size_t count, const Job& job) {
  std::atomic<std::size_t> next{0};
  std::atomic<bool> failed{false};
  std::exception_ptr error;
  std::mutex errorMutex;
  const auto body = [&](int thread) {
    try {
      Worker worker(shared);
      for (std::size_t i = next++; i < count && !failed; i = next++) {
        job(worker, thread, i);
      }
    } catch (...) {
      const std::lock_guard<std::mutex> lock(errorMutex);
      if (!error) {
        error = std::current_exception();
      }
      failed = true;
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) {
    pool.emplace_back(body, t);
  }
  body(0);
  for (std::thread& thread : pool) {
    thread.join();
  }
  if (error) {
    std::rethrow_exception(error);
  }
}

std::string frameName(std::int64_t k) {
  char name[32];
  std::snprintf(name, sizeof(name), "frame_%05lld.png", static_cast<long long>(k));
  return name;
}

/// The options of the input files, what is drawn and how (in --help order, first part).
void addInputOptions(CLI::App& app, CommandLine& options) {
  app.add_option("simulation", options.simulation, "Simulation output (.afsim) from offlineSimulator")->required();
  app.add_option("--mesh", options.mesh, "The tet mesh the simulation ran on (.veg, .node/.ele, .msh)");
  app.add_option("--scene", options.scene, "The scene the simulation ran (its mesh and fixed vertices are used)");
  app.add_option("-o,--output", options.output, "Folder for frame_NNNNN.png (created)")->capture_default_str();
  app.add_option("--frames", options.frames, "Frames to draw, start:stop:step (stop exclusive; default all)");
  app.add_option("--width", options.width, "Image width in pixels")
      ->check(asyncfem::cli::inRange(16, 4096))
      ->capture_default_str();
  app.add_option("--height", options.height, "Image height in pixels")
      ->check(asyncfem::cli::inRange(16, 4096))
      ->capture_default_str();
  app.add_option("--warp", options.warp, "Warping of the linear displacement: none, rotation-strain, modal")
      ->check(CLI::IsMember({"none", "rotation-strain", "modal"}))
      ->capture_default_str();
  app.add_option("--tint-set", options.tintSets,
                 "Set (vertex or element set) drawn in a tint colour, e.g. a fast region; repeat it for several "
                 "sets: the first gets --tint-color, the next ones blue, green, purple, ...");
  app.add_flag("--tint-regions", options.tintRegions,
               "Tint the vertices of fast regions (step ratio above 1) in --tint-color, deeper for larger ratios "
               "(ratio 2 light, 16 and above full): each frame's regions when the .afsim records them (scene key "
               "\"output\": {\"regions\": true}, the default for run-time regions), else the scene's fixed regions");
  app.add_option("--tint-color", options.tintColor, "Tint colour r,g,b in [0, 1]")
      ->delimiter(',')
      ->expected(3)
      ->check(asyncfem::cli::inRange(0.0, 1.0));
  app.add_option("--fixed-set", options.fixedSets,
                 "With --mesh: vertex sets held fixed in the simulation (rotation-strain warping keeps them)")
      ->delimiter(',');
  app.add_option("--render-mesh", options.renderMesh,
                 "Surface mesh (any format assimp reads) embedded in the tet mesh");
  app.add_option("--interp", options.interp,
                 "Vega .interp weights of --render-mesh (an OBJ) instead of locating its vertices in the tet mesh");
  app.add_flag("--ground", options.ground, "Draw a checkered ground plane with a shadow under the object");
  app.add_flag("--no-obstacles", options.noObstacles,
               "Do not draw the scene's contact spheres (drawn by default when the scene has them)");
  app.add_option("--compare", options.compare, "Second .afsim of the same mesh, drawn on the right");
  app.add_option("--labels", options.labels, "Labels of the two runs with --compare, \"left,right\"");
}

/// The options of what is made of the frames besides the PNG files (in --help order, third part).
void addMediaOptions(CLI::App& app, CommandLine& options) {
  app.add_option("--video", options.video,
                 "Also encode the drawn frames into this video (.mp4, .mkv, .webm, .gif) with ffmpeg");
  app.add_option("--fps", options.fps, "Frames per second of --video")
      ->check(asyncfem::cli::inRange(0.1, 1000.0))
      ->capture_default_str();
  app.add_option(
      "--contact-sheet", options.contactSheet,
      "Also write the drawn frames as one PNG grid, each labelled with its time (choose them with --frames)");
  app.add_option("--sheet-columns", options.sheetColumns, "Columns of --contact-sheet")
      ->check(asyncfem::cli::inRange(1, 64))
      ->capture_default_str();
}

/// The options of the camera, the image quality and the console (in --help order, second part).
void addViewOptions(CLI::App& app, CommandLine& options) {
  app.add_option("--camera-position", options.cameraPosition, "Eye position x,y,z (with --camera-target)")
      ->delimiter(',')
      ->expected(3);
  app.add_option("--camera-target", options.cameraTarget, "Point looked at x,y,z (with --camera-position)")
      ->delimiter(',')
      ->expected(3);
  app.add_option("--camera-up", options.cameraUp, "Up direction x,y,z")->delimiter(',')->expected(3);
  app.add_option("--view-direction", options.viewDirection,
                 "Fitted camera: direction from the object to the eye x,y,z (default 0.45,0.35,1)")
      ->delimiter(',')
      ->expected(3);
  app.add_option("--fov", options.fieldOfView, "Vertical field of view in degrees")
      ->check(asyncfem::cli::inRange(1.0, 170.0))
      ->capture_default_str();
  app.add_option("--supersampling", options.supersampling, "Antialiasing: render s x s samples per pixel")
      ->check(asyncfem::cli::inRange(1, 4))
      ->capture_default_str();
  app.add_option("-j,--threads", options.threads, "Rendering threads (default: the number of cores, at most 8)")
      ->check(asyncfem::cli::inRange(1, 64));
  app.add_flag("--progress", options.progress, "Draw the progress bar even when stderr is not a terminal");
  app.add_flag("-q,--quiet", options.quiet, "Print nothing but errors");
}

/// Options that cannot go together, found after parsing.
void checkOptionCombinations(const CommandLine& options) {
  if (options.mesh && options.scene) {
    throw Error(
        "give the mesh with --mesh FILE or --scene SCENE.json, not both (without either, the scene the "
        "simulation file records is used)");
  }
  if (options.cameraPosition.empty() != options.cameraTarget.empty()) {
    throw Error("--camera-position and --camera-target go together");
  }
  if (options.labels && !options.compare) {
    throw Error("--labels needs --compare");
  }
  if (options.interp && !options.renderMesh) {
    throw Error("--interp needs --render-mesh (the OBJ its weights belong to)");
  }
  if (options.fps != 30.0 && !options.video) {
    throw Error("--fps needs --video");
  }
}

/// The simulation file, and with --compare the second one, labelled by --labels or by
/// their file names.
std::vector<Run> namedRuns(const CommandLine& options) {
  std::vector<Run> runs;
  runs.push_back({fs::path(options.simulation).stem().string(), options.simulation});
  if (options.compare) {
    runs.push_back({fs::path(*options.compare).stem().string(), *options.compare});
    if (options.labels) {
      const std::size_t comma = options.labels->find(',');
      if (comma == std::string::npos || options.labels->find(',', comma + 1) != std::string::npos) {
        throw Error("--labels \"" + *options.labels + "\": expected two labels separated by one comma");
      }
      runs[0].label = options.labels->substr(0, comma);
      runs[1].label = options.labels->substr(comma + 1);
    }
  }
  return runs;
}

/// What the simulation files hold together.
struct RunsExtent {
  std::int64_t numFrames = -1;  ///< complete frames of the shorter file
  std::int64_t numVertices = 0;
};

/// Opens every run once: it exists, holds a complete frame, and all runs have the same
/// vertex count. Warns (unless quiet) about a partial last frame.
RunsExtent checkRuns(const std::vector<Run>& runs, bool quiet) {
  RunsExtent extent;
  for (const Run& run : runs) {
    if (!fs::exists(run.file)) {
      throw Error(run.file.string() + ": no such simulation file");
    }
    SimulationReader reader(run.file);
    if (reader.hasTruncatedFrame() && !quiet) {
      std::cerr << "frameRenderer: warning: " << run.file.string() << " ends in a partial frame ("
                << reader.truncatedTrailingBytes() << " bytes, an interrupted run); it is ignored\n";
    }
    if (reader.numFrames() == 0) {
      throw Error(run.file.string() + ": holds no complete frame" +
                  (reader.hasTruncatedFrame() ? " (the file is truncated inside its first frame)" : ""));
    }
    if (extent.numVertices != 0 && reader.numVertices() != extent.numVertices) {
      throw Error(run.file.string() + ": " + std::to_string(reader.numVertices()) + " vertices, but " +
                  runs.front().file.string() + " has " + std::to_string(extent.numVertices));
    }
    extent.numVertices = reader.numVertices();
    extent.numFrames = extent.numFrames < 0 ? reader.numFrames() : std::min(extent.numFrames, reader.numFrames());
  }
  return extent;
}

/// Obstacle colour: a warm grey, apart from the default surface colour and the tints.
const Eigen::Vector3f kObstacleColor(0.56F, 0.52F, 0.47F);

/// The scene's contact spheres as surfaces to draw beside the mesh.
void addObstacles(const std::vector<ContactSphere>& spheres, Shared& shared) {
  for (const ContactSphere& sphere : spheres) {
    shared.obstacles.push_back(sphereSurface(sphere.center, sphere.radius));
    shared.obstacleColors.push_back(kObstacleColor.replicate(1, shared.obstacles.back().vertices.cols()));
  }
}

/// The mesh, and the vertices held fixed in the simulation: from --scene, from the scene
/// the file records, or from --mesh. Only the problem is built: no matrix, no factorization.
void loadMesh(const CommandLine& options, std::int64_t numVertices, Shared& shared) {
  std::vector<std::string> warnings;
  if (options.scene || !options.mesh) {
    const SimulationFileHeader header = SimulationReader(shared.runs.front().file).header();
    const std::shared_ptr<const Problem> problem =
        options.scene ? buildProblem(loadScene(*options.scene), &warnings)
                      : recordedSceneProblem(header, shared.runs.front().file.string(), &warnings);
    shared.scenePath = options.scene ? *options.scene : header.scenePath;
    const Scene scene = loadScene(shared.scenePath);
    shared.sceneGround = scene.contact.ground;
    if (!options.noObstacles) addObstacles(scene.contact.spheres, shared);
    if (options.tintRegions && !header.hasRegionRatios) shared.fixedRegionRatios = fixedRegionRatios(scene, *problem);
    shared.mesh = problem->sharedMesh();
    shared.fixedVertices = problem->fixedVertices();
    shared.assemblies = problem->assemblies();
  } else {
    auto mesh = std::make_shared<TetMesh>(readMeshCollectingWarnings(*options.mesh, warnings));
    for (const std::string& set : options.fixedSets) {
      const std::vector<int> vertices = mesh->setVertices(set);
      shared.fixedVertices.insert(shared.fixedVertices.end(), vertices.begin(), vertices.end());
    }
    shared.mesh = std::move(mesh);
  }
  if (!options.quiet) {
    for (const std::string& warning : warnings) std::cerr << "frameRenderer: warning: " << warning << '\n';
  }
  const std::string meshName = options.scene ? *options.scene : options.mesh ? *options.mesh : "the recorded scene";
  if (shared.mesh->numVertices() != numVertices) {
    throw Error(shared.runs.front().file.string() + " has " + std::to_string(numVertices) + " vertices but the mesh (" +
                meshName + ") has " + std::to_string(shared.mesh->numVertices()) +
                ": the simulation did not run on this mesh");
  }
}

/// Per surface vertex colours with the --tint-set sets tinted: the first set in
/// --tint-color, the others in colours far from it and from the surface.
Eigen::Matrix3Xf tintedTetColors(const CommandLine& options, const Shared& shared,
                                 const Eigen::Vector3f& surfaceColor) {
  static const Eigen::Vector3f palette[] = {
      {0.25f, 0.45f, 0.95f}, {0.2f, 0.75f, 0.3f}, {0.65f, 0.3f, 0.8f}, {0.95f, 0.8f, 0.15f}, {0.1f, 0.75f, 0.8f}};
  Eigen::Matrix3Xf tetColors = surfaceColor.replicate(1, shared.mesh->numVertices());
  for (std::size_t i = 0; i < options.tintSets.size(); ++i) {
    VertexSelection selection;
    selection.sets.push_back(options.tintSets[i]);
    std::vector<int> tinted;
    try {
      tinted = selectVertices(*shared.mesh, selection);
    } catch (const SelectionError& error) {
      throw Error("--tint-set " + options.tintSets[i] + ": " + error.what());
    }
    const Eigen::Vector3f tint = i == 0
                                     ? Eigen::Vector3f(options.tintColor[0], options.tintColor[1], options.tintColor[2])
                                     : palette[(i - 1) % (sizeof(palette) / sizeof(palette[0]))];
    for (const int v : tinted) tetColors.col(v) = tint;
  }
  return tetColors;
}

/// base (per tet vertex) with the vertices of step ratio above 1 tinted, deeper for larger
/// ratios: a weight of 0.4 + 0.15 log2(ratio), from 0.55 at ratio 2 to 1 at 16 and above.
template <typename Ratio>
Eigen::Matrix3Xf tintByRatio(const Eigen::Matrix3Xf& base, const Eigen::Vector3f& tint,
                             const std::vector<Ratio>& ratios) {
  Eigen::Matrix3Xf colors = base;
  for (Eigen::Index v = 0; v < colors.cols() && v < std::ssize(ratios); ++v) {
    const auto ratio = static_cast<float>(ratios[static_cast<std::size_t>(v)]);
    if (ratio <= 1.0F) continue;
    const float weight = std::min(1.0F, 0.4F + (0.15F * std::log2(ratio)));
    colors.col(v) = ((1.0F - weight) * base.col(v)) + (weight * tint);
  }
  return colors;
}

/// The colours of the drawn surface: --tint-set sets, and with --tint-regions the fixed
/// regions of the scene or (set up here, applied per frame) the ratios each frame records.
/// A file that records no ratios and whose scene has no fixed regions is an error.
void chooseSurfaceColors(const CommandLine& options, const Eigen::Vector3f& surfaceColor, Shared& shared) {
  if (options.tintSets.empty() && !options.tintRegions) return;
  const Eigen::Matrix3Xf base = tintedTetColors(options, shared, surfaceColor);
  const Eigen::Vector3f tint(options.tintColor[0], options.tintColor[1], options.tintColor[2]);
  if (options.tintRegions && SimulationReader(shared.runs.front().file).header().hasRegionRatios) {
    shared.regionBase = base;
    shared.regionTint = tint;
  } else if (options.tintRegions && shared.fixedRegionRatios) {
    shared.colors = shared.surface.interpolate(tintByRatio(base, tint, *shared.fixedRegionRatios));
  } else if (options.tintRegions) {
    throw Error("--tint-regions: " + shared.runs.front().file.string() + " does not record region ratios, and " +
                (options.mesh ? "--mesh gives no scene, so there are" : "its scene has") +
                " no fixed regions to tint: record them by adding \"output\": {\"regions\": true} to the scene "
                "(the default for run-time regions) and running offlineSimulator again");
  } else {
    shared.colors = shared.surface.interpolate(base);
  }
}

/// The box of the rest shape and of every frame of every run (so that renders of
/// different frame selections share one camera), computed on up to maxThreads threads.
BoundingBox boundsOfAllFrames(const Shared& shared, int maxThreads, std::int64_t numFrames) {
  const std::size_t framesPerRun = static_cast<std::size_t>(numFrames + 1);
  std::vector<BoundingBox> frameBoxes(shared.runs.size() * framesPerRun);
  forEachParallel(shared, std::min(maxThreads, static_cast<int>(frameBoxes.size())), frameBoxes.size(),
                  [&](Worker& worker, int, std::size_t i) {
                    const std::size_t r = i / framesPerRun;
                    const std::int64_t k = static_cast<std::int64_t>(i % framesPerRun) - 1;
                    const Eigen::Matrix3Xd x = worker.surfacePositions(shared, r, k);
                    frameBoxes[i] = {x.rowwise().minCoeff(), x.rowwise().maxCoeff()};
                  });
  BoundingBox box = frameBoxes.front();
  for (const BoundingBox& b : frameBoxes) {
    box.min = box.min.cwiseMin(b.min);
    box.max = box.max.cwiseMax(b.max);
  }
  return box;
}

/// Where the panels go in the image: one, or two side by side under a label bar.
struct PanelLayout {
  int bar = 0;  ///< height of the label bar (0: one run, no bar)
  int leftWidth = 0;
  int panelHeight = 0;

  PanelLayout(const CommandLine& options, std::size_t numRuns)
      : bar(numRuns > 1 ? std::max(14, options.height / 14) : 0),
        leftWidth(numRuns > 1 ? options.width / 2 : options.width),
        panelHeight(options.height - bar) {}
  int panelWidth(const CommandLine& options, std::size_t r) const {
    return r == 0 ? leftWidth : options.width - leftWidth;
  }
};

/// The camera given by --camera-position and --camera-target, or fitted to box.
Camera chooseCamera(const CommandLine& options, const BoundingBox& box, const PanelLayout& layout,
                    const Eigen::Vector3d& up) {
  Camera camera;
  if (!options.cameraPosition.empty()) {
    camera.position = toVector(options.cameraPosition);
    camera.target = toVector(options.cameraTarget);
    camera.up = up;
    camera.verticalFieldOfViewDegrees = options.fieldOfView;
    return camera;
  }
  const Eigen::Vector3d direction =
      options.viewDirection.empty() ? defaultViewDirection() : toVector(options.viewDirection);
  return fitCamera(box, static_cast<double>(layout.leftWidth) / layout.panelHeight, direction, up, options.fieldOfView);
}

/// The floor of --ground: at the scene's contact.ground when it has one perpendicular to
/// the camera's up direction (so bodies rest on their shadow), else under the lowest point
/// of all frames.
GroundPlane chooseGround(const Shared& shared, const BoundingBox& box, const Eigen::Vector3d& up, bool quiet) {
  if (shared.sceneGround) {
    if (shared.sceneGround->normal.dot(up.normalized()) > 1.0 - 1e-9) {
      return groundAt(box, up, shared.sceneGround->offset);
    }
    if (!quiet) {
      std::cerr << "frameRenderer: warning: the scene's contact.ground is not perpendicular to --camera-up; the "
                   "floor is drawn under the lowest point of all frames instead\n";
    }
  }
  return groundBelow(box, up);
}

/// Seconds spent drawing the frames: wall time, and summed over the threads the time
/// spent rendering and writing PNG files.
struct RenderTimes {
  double wall = 0.0;
  double render = 0.0;
  double png = 0.0;
};

/// What every frame is drawn with.
struct FrameSetup {
  const PanelLayout& layout;
  const Camera& camera;
  const RenderStyle& style;
};

/// Frame k of every run drawn with the worker's readers, panels side by side under their
/// labels when there are two. own: this thread's renderers, one per panel, made on first use.
Image drawFrame(Worker& worker, std::vector<std::unique_ptr<OffscreenRenderer>>& own, const CommandLine& options,
                const Shared& shared, const FrameSetup& setup, std::int64_t k) {
  own.resize(shared.runs.size());
  std::vector<Image> panels;
  for (std::size_t r = 0; r < shared.runs.size(); ++r) {
    if (!own[r]) {
      own[r] = std::make_unique<OffscreenRenderer>(setup.layout.panelWidth(options, r), setup.layout.panelHeight,
                                                   options.supersampling);
    }
    const Eigen::Matrix3Xd x = worker.surfacePositions(shared, r, k);
    std::optional<Eigen::Matrix3Xf> frameColors;  // this frame's fast regions (--tint-regions)
    if (shared.regionBase && worker.readers[r]->header().hasRegionRatios) {
      frameColors =
          shared.surface.interpolate(tintByRatio(*shared.regionBase, shared.regionTint, worker.frame.regionRatios));
    }
    const Eigen::Matrix3Xf* colors = frameColors ? &*frameColors : shared.colors ? &*shared.colors : nullptr;
    std::vector<DrawSurface> surfaces{{x, shared.surface.triangles(), colors}};
    for (std::size_t o = 0; o < shared.obstacles.size(); ++o) {
      surfaces.push_back({shared.obstacles[o].vertices, shared.obstacles[o].triangles, &shared.obstacleColors[o]});
    }
    panels.push_back(own[r]->render(surfaces, setup.camera, setup.style));
  }
  if (panels.size() == 1) {
    return std::move(panels.front());
  }
  std::vector<std::string> labels;
  for (const Run& run : shared.runs) {
    labels.push_back(run.label);
  }
  return composeSideBySide(panels, labels, setup.layout.bar);
}

/// Draws the frames on `threads` threads into options.output, one renderer (OSMesa
/// context) per thread and panel, reporting progress.
RenderTimes renderFrames(const CommandLine& options, const Shared& shared, const std::vector<std::int64_t>& frames,
                         int threads, const FrameSetup& setup) {
  fs::create_directories(options.output);
  cli::ProgressReporter progress("frameRenderer", cli::chooseProgressStyle(options.quiet, options.progress),
                                 static_cast<int>(frames.size()));
  std::atomic<int> done{0};
  // Panels may differ in width by one, so each has its own renderer.
  std::vector<std::vector<std::unique_ptr<OffscreenRenderer>>> renderers(static_cast<std::size_t>(threads));
  std::vector<double> renderSeconds(static_cast<std::size_t>(threads), 0.0);
  std::vector<double> pngSeconds(static_cast<std::size_t>(threads), 0.0);
  Stopwatch renderWatch;
  renderWatch.start();
  try {
    forEachParallel(shared, threads, frames.size(), [&](Worker& worker, int thread, std::size_t i) {
      Stopwatch watch;
      watch.start();
      const Image image =
          drawFrame(worker, renderers[static_cast<std::size_t>(thread)], options, shared, setup, frames[i]);
      renderSeconds[static_cast<std::size_t>(thread)] += watch.stop();
      watch.start();
      writePng(fs::path(options.output) / frameName(frames[i]), image);
      pngSeconds[static_cast<std::size_t>(thread)] += watch.stop();
      progress.update(++done);
    });
  } catch (...) {
    progress.finish();
    throw;
  }
  progress.finish();
  RenderTimes times;
  times.wall = renderWatch.stop();
  for (int t = 0; t < threads; ++t) {
    times.render += renderSeconds[static_cast<std::size_t>(t)];
    times.png += pngSeconds[static_cast<std::size_t>(t)];
  }
  return times;
}

/// The summary on stdout.
void printSummary(const CommandLine& options, const Shared& shared, std::size_t numFramesDrawn, int threads,
                  double totalSeconds, double boundsSeconds, const RenderTimes& times) {
  const double frameCount = static_cast<double>(numFramesDrawn);
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(2);
  out << "frameRenderer: " << numFramesDrawn << " frames" << (options.frames.empty() ? "" : " (" + options.frames + ")")
      << " of " << shared.runs.front().file.string();
  if (shared.runs.size() > 1) {
    out << " and " << shared.runs[1].file.string();
  }
  out << " -> " << (fs::path(options.output) / "frame_NNNNN.png").string() << " (" << options.width << " x "
      << options.height << "), " << totalSeconds << " s\n";
  out << "  surface     " << shared.surfaceName << ", " << shared.surface.numSurfaceVertices() << " vertices, "
      << shared.surface.triangles().size() << " triangles";
  if (shared.surface.numOutsideVertices() > 0) {
    out << " (" << shared.surface.numOutsideVertices() << " outside the mesh, up to "
        << shared.surface.maxOutsideDistance() << " away)";
  }
  out << "\n  problem     " << (options.mesh ? "mesh file, no scene" : "mesh and fixed vertices of the scene") << ": "
      << shared.assemblies << " matrices assembled, no factorization for the simulation\n";
  out << "  warping     " << options.warp << "\n";
  out << "  camera      " << (options.cameraPosition.empty() ? "fitted to all frames" : "given") << ", bounds "
      << boundsSeconds << " s\n";
  out << "  per frame   " << 1e3 * times.wall / frameCount << " ms wall on " << threads
      << (threads == 1 ? " thread" : " threads") << " (per thread: draw " << 1e3 * times.render / frameCount
      << " ms, PNG " << 1e3 * times.png / frameCount << " ms)\n";
  std::cout << out.str() << std::flush;
}

/// Parses the command line into options; the exit status when there is nothing to run
/// (--help, a usage error).
std::optional<int> parseCommandLine(int argc, char** argv, CommandLine& options) {
  CLI::App app{"Draws the frames of an .afsim simulation file (docs/simulation-output.md) as PNG images."};
  addInputOptions(app, options);
  addViewOptions(app, options);
  addMediaOptions(app, options);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "frameRenderer: " << e.what() << " (see --help)\n";
    return 2;
  }
  checkOptionCombinations(options);
  return std::nullopt;
}

/// The surface drawn: --render-mesh (with --interp: placed by Vega's weights), a Vega
/// config scene's secondary render mesh with its .interp weights, or the tet mesh's boundary.
SurfaceEmbedding drawnSurface(const CommandLine& options, Shared& shared) {
  if (options.renderMesh) {
    shared.surfaceName = *options.renderMesh;
    return options.interp ? embedWithVegaInterpolation(*shared.mesh, *options.renderMesh, *options.interp)
                          : SurfaceEmbedding::embed(*shared.mesh, loadSurfaceMesh(*options.renderMesh));
  }
  if (!shared.scenePath.empty() && isVegaConfigPath(shared.scenePath)) {
    const VegaConfig config = readVegaConfig(shared.scenePath);
    if (config.secondaryRenderingMesh) {
      shared.surfaceName = config.secondaryRenderingMesh->string();
      return embedWithVegaInterpolation(*shared.mesh, *config.secondaryRenderingMesh, *config.secondaryInterpolation);
    }
  }
  return SurfaceEmbedding::boundary(*shared.mesh);
}

/// The simulation files (checked first: a missing or broken file is the most common
/// mistake), the selected frames, the mesh and the surface drawn, in surfaceColor with the
/// tinted sets.
Shared openInputs(const CommandLine& options, const Eigen::Vector3f& surfaceColor, std::int64_t& numFrames,
                  std::vector<std::int64_t>& frames) {
  Shared shared;
  shared.warping = parseWarpingKind(options.warp);
  shared.runs = namedRuns(options);
  const RunsExtent extent = checkRuns(shared.runs, options.quiet);
  const std::string framesSource =
      shared.runs.size() == 1 ? shared.runs[0].file.string() : "both simulation files (the shorter one)";
  numFrames = extent.numFrames;
  frames = frames::selectFrames(frames::parseFrameSelection(options.frames), extent.numFrames, framesSource);
  loadMesh(options, extent.numVertices, shared);
  shared.surface = drawnSurface(options, shared);
  chooseSurfaceColors(options, surfaceColor, shared);
  return shared;
}

/// The video and the contact sheet of the drawn frames, as asked for; a line each on stdout
/// unless quiet.
void writeMedia(const CommandLine& options, const Shared& shared, const std::vector<std::int64_t>& frames,
                const fs::path& ffmpeg) {
  std::vector<fs::path> files;
  for (const std::int64_t k : frames) files.push_back(fs::path(options.output) / frameName(k));
  if (options.video) {
    media::encodeVideo(ffmpeg, files, *options.video, options.fps);
    if (!options.quiet) {
      std::cout << "frameRenderer: video " << *options.video << " (" << frames.size() << " frames at " << options.fps
                << " per s, ffmpeg)\n";
    }
  }
  if (options.contactSheet) {
    SimulationReader reader(shared.runs.front().file);
    std::vector<Image> tiles;
    std::vector<std::string> labels;
    for (std::size_t i = 0; i < frames.size(); ++i) {
      tiles.push_back(readPng(files[i]));
      char label[64];
      std::snprintf(label, sizeof(label), "t = %.4g s", reader.readFrame(frames[i]).time);
      labels.emplace_back(label);
    }
    const Image sheet = media::contactSheet(tiles, labels, options.sheetColumns);
    const fs::path sheetPath(*options.contactSheet);
    if (sheetPath.has_parent_path()) fs::create_directories(sheetPath.parent_path());
    writePng(sheetPath, sheet, PngCompression::standard);
    if (!options.quiet) {
      std::cout << "frameRenderer: contact sheet " << *options.contactSheet << " (" << frames.size() << " frames, "
                << sheet.width << " x " << sheet.height << ")\n";
    }
  }
}

int run(int argc, char** argv) {
  CommandLine options;
  if (const std::optional<int> status = parseCommandLine(argc, argv, options)) {
    return *status;
  }
  Stopwatch total;
  total.start();
  RenderStyle style;
  std::int64_t numFrames = 0;
  std::vector<std::int64_t> frames;
  const Shared shared = openInputs(options, style.surfaceColor, numFrames, frames);
  const fs::path ffmpeg = options.video ? media::requireFfmpeg() : fs::path();  // before any drawing

  const int maxThreads = std::max(
      1, options.threads > 0 ? options.threads : static_cast<int>(std::min(8U, std::thread::hardware_concurrency())));
  const int threads = std::min(maxThreads, static_cast<int>(frames.size()));
  const PanelLayout layout(options, shared.runs.size());
  Stopwatch boundsWatch;
  boundsWatch.start();
  const BoundingBox box = boundsOfAllFrames(shared, maxThreads, numFrames);
  const double boundsSeconds = boundsWatch.stop();
  const Eigen::Vector3d up = toVector(options.cameraUp);
  if (!(up.norm() > 0.0)) {
    throw Error("--camera-up must not be zero");
  }
  const Camera camera = chooseCamera(options, box, layout, up);
  if (options.ground) {
    style.ground = chooseGround(shared, box, up, options.quiet);
  }

  const RenderTimes times = renderFrames(options, shared, frames, threads, {layout, camera, style});
  if (!options.quiet) {
    printSummary(options, shared, frames.size(), threads, total.stop(), boundsSeconds, times);
  }
  writeMedia(options, shared, frames, ffmpeg);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  asyncfem::preferPassiveThreadWaiting(argv);
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "frameRenderer: " << e.what() << "\n";
    return 1;
  }
}
