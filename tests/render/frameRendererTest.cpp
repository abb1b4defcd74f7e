// SPDX-License-Identifier: BSD-3-Clause
// frameRenderer end to end: runs the built executable on simulation files written by the
// tests and checks its exit status, messages and the PNG files it leaves.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <asyncfem/image/png.hpp>
#include <asyncfem/render/surfaceMesh.hpp>
#include <asyncfem/simulationIO/simulationFile.hpp>
#include <asyncfem/volumetricMesh/writers.hpp>
#include <fstream>
#include <sstream>

#include "renderTestHelpers.hpp"

namespace {

namespace fs = std::filesystem;
using namespace asyncfem;

const std::string rendererPath = std::string(ASYNCFEM_BIN_DIR) + "/frameRenderer";

struct RunResult {
  int exitCode = -1;
  std::string out;
  std::string err;
};

std::string readText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

class FrameRendererTest : public ::testing::Test {
 protected:
  void SetUp() override {
    folder_ = renderTesting::freshFolder(std::string("frameRenderer-") +
                                         ::testing::UnitTest::GetInstance()->current_test_info()->name());
    mesh_ = renderTesting::renderTestBar();
    writeVeg(folder_ / "bar.veg", mesh_);
    // Six frames bending the bar a little more each time.
    SimulationFileHeader header;
    header.numVertices = mesh_.numVertices();
    header.frameInterval = 0.1;
    SimulationWriter writer(folder_ / "run.afsim", header);
    const Eigen::VectorXd bent = renderTesting::bentBar(mesh_);
    for (int k = 0; k < 6; ++k) {
      writer.appendFrame(0.1 * (k + 1), (k + 1) / 6.0 * bent);
    }
  }
  void TearDown() override { fs::remove_all(folder_); }

  RunResult run(const std::string& arguments) const {
    const std::string command =
        "cd '" + folder_.string() + "' && '" + rendererPath + "' " + arguments + " > stdout.txt 2> stderr.txt";
    const int status = std::system(command.c_str());
    RunResult result;
    result.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    result.out = readText(folder_ / "stdout.txt");
    result.err = readText(folder_ / "stderr.txt");
    return result;
  }

  /// scene.json: backward Euler on meshFile with its vertex set "xmin" fixed, six frames.
  void writeScene(const std::string& meshFile) const {
    std::ofstream(folder_ / "scene.json") << R"({
      "mesh": {"file": ")" << meshFile << R"("},
      "fixed": {"sets": ["xmin"]},
      "integrator": {"name": "backward-euler", "timestep": 0.01},
      "frames": {"rate": 10, "count": 6}
    })";
  }

  fs::path folder_;
  TetMesh mesh_;
};

TEST_F(FrameRendererTest, WritesTheSelectedFramesAtTheRequestedSize) {
  const RunResult r = run("run.afsim --mesh bar.veg --output out --frames 0:6:2 --width 96 --height 64");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.out.find("3 frames"), std::string::npos) << r.out;
  for (const int k : {0, 2, 4}) {
    char name[32];
    std::snprintf(name, sizeof(name), "frame_%05d.png", k);
    ASSERT_TRUE(fs::exists(folder_ / "out" / name)) << name;
    const Image image = readPng(folder_ / "out" / name);
    EXPECT_EQ(image.width, 96);
    EXPECT_EQ(image.height, 64);
  }
  EXPECT_FALSE(fs::exists(folder_ / "out" / "frame_00001.png"));
  EXPECT_FALSE(fs::exists(folder_ / "out" / "frame_00006.png"));
  // stderr is a file here: progress comes as plain lines, the last one at 100%.
  EXPECT_NE(r.err.find("frameRenderer: frame 3/3 (100%), elapsed "), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find('\r'), std::string::npos) << r.err;
}

TEST_F(FrameRendererTest, SameInputRendersTheSameFileTwice) {
  for (const char* out : {"a", "b"}) {
    const RunResult r =
        run(std::string("run.afsim --mesh bar.veg --frames 3 --width 80 --height 60 --ground -q -o ") + out);
    ASSERT_EQ(r.exitCode, 0) << r.err;
  }
  const std::string a = readText(folder_ / "a" / "frame_00003.png");
  EXPECT_FALSE(a.empty());
  EXPECT_EQ(a, readText(folder_ / "b" / "frame_00003.png"));
  // Also with one thread against two (each frame is drawn by one context either way).
  ASSERT_EQ(run("run.afsim --mesh bar.veg --frames 2:4 --width 80 --height 60 --ground -q -j 1 -o c").exitCode, 0);
  ASSERT_EQ(run("run.afsim --mesh bar.veg --frames 2:4 --width 80 --height 60 --ground -q -j 2 -o d").exitCode, 0);
  EXPECT_EQ(readText(folder_ / "c" / "frame_00003.png"), readText(folder_ / "d" / "frame_00003.png"));
  EXPECT_EQ(readText(folder_ / "c" / "frame_00003.png"), a);
}

// Pixels whose colour leans clearly towards one channel.
template <typename Predicate>
int countPixels(const Image& image, Predicate leans) {
  int count = 0;
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) count += leans(image.pixel(x, y)) ? 1 : 0;
  }
  return count;
}

int orangePixels(const Image& image) {
  return countPixels(image, [](const std::uint8_t* p) { return p[0] > p[2] + 40 && p[0] > p[1] + 20; });
}

int bluePixels(const Image& image) {
  return countPixels(image, [](const std::uint8_t* p) { return p[2] > p[0] + 40 && p[2] > p[1] + 20; });
}

TEST_F(FrameRendererTest, TintSetColoursItsRegionOnly) {
  ASSERT_EQ(run("run.afsim --mesh bar.veg --frames 5 --width 120 --height 80 -q -o plain").exitCode, 0);
  const RunResult r = run("run.afsim --mesh bar.veg --frames 5 --width 120 --height 80 -q -o tinted --tint-set xmax");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_EQ(orangePixels(readPng(folder_ / "plain" / "frame_00005.png")), 0);
  EXPECT_GT(orangePixels(readPng(folder_ / "tinted" / "frame_00005.png")), 20);
  const RunResult bad = run("run.afsim --mesh bar.veg --frames 5 -q -o x --tint-set nothere");
  EXPECT_EQ(bad.exitCode, 1);
  EXPECT_NE(bad.err.find("nothere"), std::string::npos) << bad.err;
}

// Several sets: the first in --tint-color (orange by default), the second in the palette's blue.
TEST_F(FrameRendererTest, SeveralTintSetsGetTheirOwnColours) {
  const RunResult one = run("run.afsim --mesh bar.veg --frames 5 --width 120 --height 80 -q -o one --tint-set xmax");
  ASSERT_EQ(one.exitCode, 0) << one.err;
  const RunResult two =
      run("run.afsim --mesh bar.veg --frames 5 --width 120 --height 80 -q -o two --tint-set xmax --tint-set xmin");
  ASSERT_EQ(two.exitCode, 0) << two.err;
  const Image single = readPng(folder_ / "one" / "frame_00005.png");
  const Image both = readPng(folder_ / "two" / "frame_00005.png");
  // The background has some blue pixels of its own: the second set adds more.
  EXPECT_GT(bluePixels(both), bluePixels(single) + 20);
  EXPECT_GT(orangePixels(both), 20);
  const RunResult bad = run("run.afsim --mesh bar.veg --frames 5 -q -o x --tint-set xmax --tint-set nothere");
  EXPECT_EQ(bad.exitCode, 1);
  EXPECT_NE(bad.err.find("--tint-set nothere: unknown set"), std::string::npos) << bad.err;
}

TEST_F(FrameRendererTest, OptionsCombine) {
  SurfaceMesh shape;
  shape.vertices.resize(3, 4);
  shape.vertices << 0.2, 1.8, 1.0, 1.0, 0.1, 0.1, 0.35, 0.1, 0.1, 0.1, 0.1, 0.35;
  shape.triangles = {{0, 1, 2}, {0, 3, 1}, {1, 3, 2}, {0, 2, 3}};
  writeObj(folder_ / "shape.obj", shape);
  for (const std::string options :
       {"--warp rotation-strain --fixed-set xmin", "--warp modal", "--render-mesh shape.obj --ground",
        "--camera-position 1,1,5 --camera-target 1,0,0 --fov 40", "--view-direction 0,1,0.2 --supersampling 1"}) {
    const RunResult r = run("run.afsim --mesh bar.veg --frames 4:6 --width 64 --height 48 -q -o out " + options);
    EXPECT_EQ(r.exitCode, 0) << options << ": " << r.err;
    EXPECT_TRUE(fs::exists(folder_ / "out" / "frame_00005.png")) << options;
  }
}

TEST_F(FrameRendererTest, CompareDrawsBothRunsSideBySide) {
  fs::copy_file(folder_ / "run.afsim", folder_ / "other.afsim");
  const RunResult r =
      run("run.afsim --mesh bar.veg --frames 1 --width 161 --height 90 -q -o out --compare other.afsim --labels "
          "\"async,single-rate\"");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const Image image = readPng(folder_ / "out" / "frame_00001.png");
  EXPECT_EQ(image.width, 161);
  EXPECT_EQ(image.height, 90);
  // The same run on both sides: the two panels (80 and 81 pixels wide) show the object.
  EXPECT_NE(image.pixel(40, 50)[0], 255);
  const RunResult labels = run("run.afsim --mesh bar.veg -q -o out --compare other.afsim --labels onlyone");
  EXPECT_EQ(labels.exitCode, 1);
  EXPECT_NE(labels.err.find("two labels"), std::string::npos) << labels.err;
}

TEST_F(FrameRendererTest, MissingSimulationFileIsAClearError) {
  const RunResult r = run("nothere.afsim --mesh bar.veg -o out");
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_EQ(r.err.rfind("frameRenderer: ", 0), 0U) << r.err;
  EXPECT_NE(r.err.find("nothere.afsim: no such simulation file"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(folder_ / "out"));
}

TEST_F(FrameRendererTest, TruncatedSimulationFileIsAClearError) {
  const std::string bytes = readText(folder_ / "run.afsim");
  std::ofstream(folder_ / "header.afsim", std::ios::binary) << bytes.substr(0, 30);
  const RunResult header = run("header.afsim --mesh bar.veg -o out");
  EXPECT_EQ(header.exitCode, 1);
  EXPECT_NE(header.err.find("header.afsim"), std::string::npos) << header.err;
  EXPECT_NE(header.err.find("truncated header"), std::string::npos) << header.err;

  std::ofstream(folder_ / "record.afsim", std::ios::binary) << bytes.substr(0, 64 + 100);
  const RunResult record = run("record.afsim --mesh bar.veg -o out");
  EXPECT_EQ(record.exitCode, 1);
  EXPECT_NE(record.err.find("holds no complete frame"), std::string::npos) << record.err;

  // A partial last frame (an interrupted run): the complete frames still render, with a
  // warning; asking for the partial one is out of range.
  const std::int64_t recordBytes = (static_cast<std::int64_t>(bytes.size()) - 64) / 6;
  std::ofstream(folder_ / "partial.afsim", std::ios::binary)
      << bytes.substr(0, static_cast<std::size_t>(64 + (5 * recordBytes) + 10));
  const RunResult partial = run("partial.afsim --mesh bar.veg --width 32 --height 32 -o out");
  EXPECT_EQ(partial.exitCode, 0) << partial.err;
  EXPECT_NE(partial.err.find("partial frame"), std::string::npos) << partial.err;
  EXPECT_TRUE(fs::exists(folder_ / "out" / "frame_00004.png"));
  const RunResult beyond = run("partial.afsim --mesh bar.veg --frames 5 -o out");
  EXPECT_EQ(beyond.exitCode, 1);
  EXPECT_NE(beyond.err.find("start 5 is beyond the 5 frames"), std::string::npos) << beyond.err;
}

TEST_F(FrameRendererTest, FramesOutOfRangeAreAClearError) {
  const RunResult r = run("run.afsim --mesh bar.veg --frames 0:20:5 -o out");
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_NE(r.err.find("frames 0:20:5: stop 20 is beyond the 6 frames of run.afsim (frames 0 to 5)"), std::string::npos)
      << r.err;
  for (const char* bad : {"--frames 3:3", "--frames a:b", "--frames 0:4:0", "--frames 1:2:3:4"}) {
    const RunResult b = run(std::string("run.afsim --mesh bar.veg -o out ") + bad);
    EXPECT_EQ(b.exitCode, 1) << bad;
    EXPECT_NE(b.err.find("frames"), std::string::npos) << bad << ": " << b.err;
  }
}

TEST_F(FrameRendererTest, VertexCountMismatchIsAClearError) {
  BoxMeshSpec spec;
  spec.cells = Eigen::Vector3i(2, 2, 2);
  writeVeg(folder_ / "small.veg", makeBoxMesh(spec));
  const RunResult r = run("run.afsim --mesh small.veg -o out");
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_NE(
      r.err.find("run.afsim has " + std::to_string(mesh_.numVertices()) + " vertices but the mesh (small.veg) has 27"),
      std::string::npos)
      << r.err;
  const RunResult neither = run("run.afsim -o out");
  EXPECT_EQ(neither.exitCode, 1);
  EXPECT_NE(neither.err.find("--mesh"), std::string::npos) << neither.err;
}

TEST_F(FrameRendererTest, SceneGivesTheMesh) {
  writeScene("bar.veg");
  const RunResult r =
      run("run.afsim --scene scene.json --frames 0 --width 48 --height 32 -q -o out --warp rotation-strain");
  EXPECT_EQ(r.exitCode, 0) << r.err;
  EXPECT_TRUE(fs::exists(folder_ / "out" / "frame_00000.png"));
}

TEST_F(FrameRendererTest, HexahedralSceneDrawsAnEmbeddedRenderMesh) {
  // A bar of 8 x 2 x 2 CUBIC elements, bent over five frames, with a render mesh (a
  // tetrahedron of four points, one 0.1 beyond the bar's end) embedded in its hexahedra.
  TetMesh cubes = renderTesting::renderTestCubeBar();
  std::vector<int> xmin;
  for (int v = 0; v < cubes.numVertices(); ++v)
    if (cubes.restPosition(v).x() == 0.0) xmin.push_back(v);
  cubes.setVertexSet("xmin", xmin);
  writeVeg(folder_ / "cubes.veg", cubes);
  SimulationFileHeader header;
  header.numVertices = cubes.numVertices();
  header.frameInterval = 0.1;
  {
    SimulationWriter writer(folder_ / "cubes.afsim", header);
    for (int k = 0; k < 6; ++k) writer.appendFrame(0.1 * k, k / 5.0 * renderTesting::bentBar(cubes));
  }
  SurfaceMesh shape;
  shape.vertices.resize(3, 4);
  shape.vertices << 0.2, 1.7, 1.0, 1.0, 0.1, 0.1, 0.35, 0.1, 0.1, 0.1, 0.1, 0.35;
  shape.triangles = {{0, 1, 2}, {0, 3, 1}, {1, 3, 2}, {0, 2, 3}};
  writeObj(folder_ / "shape.obj", shape);
  writeScene("cubes.veg");
  const RunResult r =
      run("cubes.afsim --scene scene.json --render-mesh shape.obj --frames 0:6:5 --width 64 --height 48 "
          "--camera-position 0.8,0.2,5 --camera-target 0.8,0.2,0.2 -o out");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.out.find("shape.obj, 4 vertices, 4 triangles (1 outside the mesh, up to 0.10 away)"), std::string::npos)
      << r.out;
  // The bent frame draws the surface lower down than the rest frame: the images differ.
  const Image rest = readPng(folder_ / "out" / "frame_00000.png");
  const Image bent = readPng(folder_ / "out" / "frame_00005.png");
  EXPECT_NE(rest.pixels, bent.pixels);
}

// --ground puts the floor at the scene's contact.ground: two heights give two images, and a
// scene without contact draws the floor where --mesh does (under the lowest point).
TEST_F(FrameRendererTest, GroundFollowsTheScenesContactGround) {
  const auto writeScene = [&](const std::string& name, const std::string& contact) {
    std::ofstream(folder_ / name) << R"({"mesh": {"file": "bar.veg"}, "fixed": {"sets": ["xmin"]},)" << contact
                                  << R"("integrator": {"name": "backward-euler", "timestep": 0.01},
      "frames": {"rate": 10, "count": 6}})";
  };
  writeScene("low.json", R"("contact": {"ground": {"height": -2}},)");
  writeScene("lower.json", R"("contact": {"ground": {"height": -4}},)");
  writeScene("none.json", "");
  const std::string common = "run.afsim --frames 0 --width 64 --height 48 --ground -q -j 1 -o ";
  for (const char* name : {"low", "lower", "none"}) {
    const RunResult r = run(common + name + " --scene " + name + ".json");
    ASSERT_EQ(r.exitCode, 0) << name << ": " << r.err;
  }
  ASSERT_EQ(run(common + "mesh --mesh bar.veg").exitCode, 0);
  const std::string low = readText(folder_ / "low" / "frame_00000.png");
  EXPECT_NE(low, readText(folder_ / "lower" / "frame_00000.png"));
  EXPECT_NE(low, readText(folder_ / "none" / "frame_00000.png"));
  EXPECT_EQ(readText(folder_ / "none" / "frame_00000.png"), readText(folder_ / "mesh" / "frame_00000.png"));
}

// The scene's contact spheres are drawn beside the mesh (an obstacle under the bar covers
// background pixels), and not with --no-obstacles, which draws what a scene without
// spheres draws, byte for byte.
TEST_F(FrameRendererTest, DrawsTheScenesContactSpheres) {
  const auto writeScene = [&](const std::string& name, const std::string& contact) {
    std::ofstream(folder_ / name) << R"({"mesh": {"file": "bar.veg"}, "fixed": {"sets": ["xmin"]},)" << contact
                                  << R"("integrator": {"name": "backward-euler", "timestep": 0.01},
      "frames": {"rate": 10, "count": 6}})";
  };
  writeScene("sphere.json", R"("contact": {"spheres": [{"center": [1.0, -0.5, 0.2], "radius": 0.35}]},)");
  writeScene("plain.json", "");
  const std::string common = "run.afsim --frames 0 --width 96 --height 64 -q -j 1 -o ";
  ASSERT_EQ(run(common + "sphere --scene sphere.json").exitCode, 0);
  ASSERT_EQ(run(common + "hidden --scene sphere.json --no-obstacles").exitCode, 0);
  ASSERT_EQ(run(common + "plain --scene plain.json").exitCode, 0);
  const auto background = [](const std::uint8_t* p) { return p[0] == 255 && p[1] == 255 && p[2] == 255; };
  const Image withSphere = readPng(folder_ / "sphere" / "frame_00000.png");
  const Image hidden = readPng(folder_ / "hidden" / "frame_00000.png");
  // The sphere's disc under the bar is about 10 x 10 pixels at this size: at least 40 of them.
  EXPECT_LT(countPixels(withSphere, background) + 40, countPixels(hidden, background));
  EXPECT_EQ(readText(folder_ / "hidden" / "frame_00000.png"), readText(folder_ / "plain" / "frame_00000.png"));
}

// offlineSimulator records the scene (absolute path and the fingerprint of the mesh and
// fixed vertices it built) in the .afsim header: frameRenderer then needs neither --scene
// nor --mesh, builds only the problem (no matrix, no factorization: the summary says so),
// and refuses when the scene now builds another mesh.
TEST_F(FrameRendererTest, RecordedSceneGivesTheMeshAndIsChecked) {
  std::ofstream(folder_ / "scene.json") << R"({
    "mesh": {"file": "bar.veg"},
    "fixed": {"sets": ["xmin"]},
    "gravity": [0, -9.81, 0],
    "integrator": {"name": "backward-euler", "timestep": 0.05},
    "frames": {"rate": 10, "count": 3},
    "output": {"file": "sim.afsim"}
  })";
  const std::string simulator = std::string(ASYNCFEM_BIN_DIR) + "/offlineSimulator";
  const std::string command = "cd '" + folder_.string() + "' && '" + simulator + "' scene.json -q > sim.txt 2>&1";
  ASSERT_EQ(std::system(command.c_str()), 0) << readText(folder_ / "sim.txt");
  const SimulationReader reader(folder_ / "sim.afsim");
  EXPECT_EQ(fs::path(reader.header().scenePath), fs::weakly_canonical(folder_ / "scene.json"));
  const RunResult r = run("sim.afsim --frames 2 --width 48 --height 32 -o out");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_TRUE(fs::exists(folder_ / "out" / "frame_00002.png"));
  EXPECT_NE(r.out.find("problem     mesh and fixed vertices of the scene: 0 matrices assembled, no factorization"),
            std::string::npos)
      << r.out;
  // Another boundary: the fingerprint no longer matches.
  std::ofstream(folder_ / "scene.json") << R"({
    "mesh": {"file": "bar.veg"},
    "fixed": {"sets": ["xmax"]},
    "integrator": {"name": "backward-euler", "timestep": 0.05},
    "frames": {"rate": 10, "count": 3}
  })";
  const RunResult changed = run("sim.afsim --frames 2 -q -o out2");
  EXPECT_EQ(changed.exitCode, 1);
  EXPECT_NE(changed.err.find("now builds another mesh or other fixed vertices"), std::string::npos) << changed.err;
  // --scene still overrides.
  EXPECT_EQ(run("sim.afsim --scene scene.json --frames 2 -q -o out3").exitCode, 0);
}

// Runs a shell command in folder, its output (stdout and stderr) returned.
std::string commandOutput(const fs::path& folder, const std::string& command) {
  const std::string full = "cd '" + folder.string() + "' && " + command + " > command.txt 2>&1";
  if (std::system(full.c_str()) != 0) return "failed: " + readText(folder / "command.txt");
  return readText(folder / "command.txt");
}

bool onPath(const std::string& program) { return std::system(("command -v " + program + " > /dev/null").c_str()) == 0; }

bool leftoverPartialFiles(const fs::path& folder) {
  for (const auto& entry : fs::recursive_directory_iterator(folder)) {
    if (entry.path().filename().string().find(".frameRenderer-") != std::string::npos) return true;
  }
  return false;
}

TEST_F(FrameRendererTest, VideoHoldsEveryDrawnFrame) {
  if (!onPath("ffmpeg") || !onPath("ffprobe")) {
    GTEST_SKIP() << "SKIP: ffmpeg/ffprobe not installed (Debian: apt-get install ffmpeg)";
  }
  // An odd width: H.264 in yuv420p needs even sizes, the frames are padded.
  const RunResult r =
      run("run.afsim --mesh bar.veg --frames 0:6:1 --width 97 --height 64 -o out --video movie.mp4 "
          "--fps 12");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_NE(r.out.find("video movie.mp4 (6 frames at 12 per s, ffmpeg)"), std::string::npos) << r.out;
  ASSERT_TRUE(fs::exists(folder_ / "movie.mp4"));
  EXPECT_GT(fs::file_size(folder_ / "movie.mp4"), 1000U);
  const std::string probe = commandOutput(
      folder_,
      "ffprobe -v error -count_frames -select_streams v:0 -show_entries stream=nb_read_frames,width,height,codec_name "
      "-of default=noprint_wrappers=1 movie.mp4");
  EXPECT_NE(probe.find("nb_read_frames=6"), std::string::npos) << probe;
  EXPECT_NE(probe.find("codec_name=h264"), std::string::npos) << probe;
  EXPECT_NE(probe.find("width=98"), std::string::npos) << probe;
  EXPECT_FALSE(leftoverPartialFiles(folder_));
  // A selection with a step: the video holds the selected frames only.
  ASSERT_EQ(
      run("run.afsim --mesh bar.veg --frames 0:6:2 --width 64 --height 48 -q -o out2 --video sub/two.mkv").exitCode, 0);
  EXPECT_NE(commandOutput(folder_,
                          "ffprobe -v error -count_frames -select_streams v:0 -show_entries "
                          "stream=nb_read_frames -of default=noprint_wrappers=1 sub/two.mkv")
                .find("nb_read_frames=3"),
            std::string::npos);
}

TEST_F(FrameRendererTest, VideoFailuresLeaveNoVideoBehind) {
  // Without ffmpeg on PATH: a clear error before any frame is drawn.
  const std::string command = "cd '" + folder_.string() + "' && PATH=/nonexistent '" + rendererPath +
                              "' run.afsim --mesh bar.veg -o out --video movie.mp4 > stdout.txt 2> stderr.txt";
  const int status = std::system(command.c_str());
  EXPECT_EQ(WIFEXITED(status) ? WEXITSTATUS(status) : -1, 1);
  const std::string err = readText(folder_ / "stderr.txt");
  EXPECT_NE(err.find("frameRenderer: --video needs ffmpeg, which is not on PATH"), std::string::npos) << err;
  EXPECT_NE(err.find("apt-get install ffmpeg"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(folder_ / "movie.mp4"));
  EXPECT_FALSE(fs::exists(folder_ / "out"));
  EXPECT_EQ(run("run.afsim --mesh bar.veg -o out --fps 10").exitCode, 1);  // --fps without --video
  if (!onPath("ffmpeg")) {
    GTEST_SKIP() << "SKIP: ffmpeg not installed, its failure is not tried";
  }
  // ffmpeg fails (a container it does not know): an error with its message, no file claimed.
  const RunResult r =
      run("run.afsim --mesh bar.veg --frames 0:2 --width 32 --height 32 -q -o out --video bad.notavideo");
  EXPECT_EQ(r.exitCode, 1);
  EXPECT_NE(r.err.find("ffmpeg failed to encode bad.notavideo"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(folder_ / "bad.notavideo"));
  EXPECT_FALSE(leftoverPartialFiles(folder_));
}

TEST_F(FrameRendererTest, ContactSheetIsAGridOfLabelledFrames) {
  const RunResult r =
      run("run.afsim --mesh bar.veg --frames 0:5 --width 80 --height 60 -o out --contact-sheet "
          "sheet.png --sheet-columns 2");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  const int bar = 14;  // label bar under each 60-pixel tile
  const Image sheet = readPng(folder_ / "sheet.png");
  EXPECT_EQ(sheet.width, 2 * 80);
  EXPECT_EQ(sheet.height, 3 * (60 + bar));  // five frames in two columns
  EXPECT_NE(r.out.find("contact sheet sheet.png (5 frames, 160 x 222)"), std::string::npos) << r.out;
  // Tile 3 (row 1, column 1) is frame 3 as drawn; its label bar holds dark text.
  const Image frame3 = readPng(folder_ / "out" / "frame_00003.png");
  bool same = true;
  for (int y = 1; y < 60 && same; ++y) {
    for (int x = 1; x < 80 && same; ++x) same = sheet.at(80 + x, (60 + bar) + y) == frame3.at(x, y);
  }
  EXPECT_TRUE(same);
  int dark = 0;
  for (int y = 60; y < 60 + bar; ++y) {
    for (int x = 0; x < 80; ++x) dark += sheet.at(x, y).r < 128 ? 1 : 0;
  }
  EXPECT_GT(dark, 20);  // "t = 0.1 s"
  // Four columns by default: one row of four.
  ASSERT_EQ(
      run("run.afsim --mesh bar.veg --frames 0:4 --width 40 --height 30 -q -o out2 --contact-sheet s2.png").exitCode,
      0);
  const Image row = readPng(folder_ / "s2.png");
  EXPECT_EQ(row.width, 4 * 40);
  EXPECT_EQ(row.height, 30 + 14);
}

// --tint-regions: each frame's recorded step ratios (header flag bit 1). Frame 0 has no fast
// vertex and is drawn exactly as without the option; frame 4's region (ratio 16, x >= 1)
// is larger than frame 2's (ratio 8, x >= 1.6), so more pixels are tinted.
TEST_F(FrameRendererTest, TintRegionsFollowsEachFramesRecordedRegions) {
  SimulationFileHeader header;
  header.numVertices = mesh_.numVertices();
  header.frameInterval = 0.1;
  header.hasRegionRatios = true;
  {
    SimulationWriter writer(folder_ / "regions.afsim", header);
    const Eigen::VectorXd bent = renderTesting::bentBar(mesh_);
    for (int k = 0; k < 6; ++k) {
      std::vector<int> ratios(static_cast<std::size_t>(mesh_.numVertices()), 1);
      for (int v = 0; v < mesh_.numVertices(); ++v) {
        const double x = mesh_.restPosition(v).x();
        if (k == 2 && x >= 1.6 - 1e-9) ratios[static_cast<std::size_t>(v)] = 8;
        if (k == 4 && x >= 1.0 - 1e-9) ratios[static_cast<std::size_t>(v)] = 16;
      }
      writer.appendFrame(0.1 * (k + 1), 0.5 * bent, ratios);
    }
  }
  const std::string common = "regions.afsim --mesh bar.veg --frames 0:5:2 --width 120 --height 80 -q -j 1 ";
  ASSERT_EQ(run(common + "-o plain").exitCode, 0);
  const RunResult r = run(common + "-o tinted --tint-regions --contact-sheet sheet.png");
  ASSERT_EQ(r.exitCode, 0) << r.err;
  EXPECT_EQ(readText(folder_ / "plain" / "frame_00000.png"), readText(folder_ / "tinted" / "frame_00000.png"));
  const int small = orangePixels(readPng(folder_ / "tinted" / "frame_00002.png"));
  const int large = orangePixels(readPng(folder_ / "tinted" / "frame_00004.png"));
  EXPECT_EQ(orangePixels(readPng(folder_ / "plain" / "frame_00004.png")), 0);
  EXPECT_GT(small, 20);
  EXPECT_GT(large, small + 20) << "frame 2: " << small << ", frame 4: " << large;
  EXPECT_TRUE(fs::exists(folder_ / "sheet.png"));
}

// Without recorded ratios: the scene's fixed regions, constant over the frames, or an error
// saying how to record them.
TEST_F(FrameRendererTest, TintRegionsUsesFixedRegionsOrSaysHowToRecordThem) {
  std::ofstream(folder_ / "scene.json") << R"({
    "mesh": {"file": "bar.veg"},
    "fixed": {"sets": ["xmin"]},
    "integrator": {"name": "async", "timestep": 0.01,
                   "options": {"regions": [{"name": "tip", "ratio": 4, "boxes": [{"min": [1.5, -1, -1], "max": [3, 1, 1]}]}]}},
    "frames": {"rate": 10, "count": 6}
  })";
  const RunResult fixed =
      run("run.afsim --scene scene.json --frames 5 --width 120 --height 80 -q -o fixed --tint-regions");
  ASSERT_EQ(fixed.exitCode, 0) << fixed.err;
  EXPECT_GT(orangePixels(readPng(folder_ / "fixed" / "frame_00005.png")), 20);

  const RunResult none = run("run.afsim --mesh bar.veg --frames 5 -q -o none --tint-regions");
  EXPECT_EQ(none.exitCode, 1);
  const std::string expected =
      "frameRenderer: --tint-regions: run.afsim does not record region ratios, and --mesh gives no scene, so there "
      "are no fixed regions to tint: record them by adding \"output\": {\"regions\": true} to the scene";
  EXPECT_NE(none.err.find(expected), std::string::npos) << none.err;
}

}  // namespace
