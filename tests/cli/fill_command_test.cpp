// `sketchdrape fill`: the JSON report equals what the library computes for the command's
// documented region, --obj and --png write what they say, and bad --sides exit 2 with a
// sentence and write nothing.

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <numeric>
#include <sstream>

#include "meshing/patch_fill.hpp"
#include "src/render/image.hpp"
#include "tests/cli/run_command.hpp"

namespace sd::test {
namespace {

namespace fs = std::filesystem;

// The region `fill` meshes (docs/meshing.md, "Command line"): corners on the unit circle at
// angles proportional to the counts before them, starting at 90°, straight sides; for n = 2
// each side is the circular arc (8 points per edge).
std::vector<Eigen::MatrixX3d> command_region(const std::vector<int>& counts) {
  const int total = std::accumulate(counts.begin(), counts.end(), 0);
  auto on_circle = [&](double position) {
    const double angle = 2 * std::numbers::pi * position / total + std::numbers::pi / 2;
    return Eigen::RowVector3d(std::cos(angle), std::sin(angle), 0.0);
  };
  std::vector<Eigen::MatrixX3d> sides;
  int start = 0;
  for (const int count : counts) {
    const int points = counts.size() == 2 ? count * 8 + 1 : 2;
    Eigen::MatrixX3d polyline(points, 3);
    for (int k = 0; k < points; ++k)
      polyline.row(k) = on_circle(start + static_cast<double>(count) * k / (points - 1));
    sides.push_back(polyline);
    start += count;
  }
  for (size_t i = 0; i < sides.size(); ++i)
    sides[i].bottomRows<1>() = sides[(i + 1) % sides.size()].topRows<1>();
  return sides;
}

class FillCommand : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("sd_fill_cli_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(FillCommand, JsonFieldsMatchTheLibrary) {
  for (const std::vector<int>& counts :
       std::vector<std::vector<int>>{{5, 6, 3, 6, 4}, {6, 4, 4, 2}, {2, 8, 4}, {4, 6}}) {
    std::string arg;
    for (size_t i = 0; i < counts.size(); ++i) arg += (i ? "," : "") + std::to_string(counts[i]);
    const CommandResult run = run_sketchdrape("fill --sides " + arg + " --json");
    ASSERT_EQ(run.exit_code, 0) << run.output;
    const nlohmann::json report = nlohmann::json::parse(run.output);
    const meshing::FilledPatch patch =
        meshing::fill_region(command_region(counts), counts, meshing::FillGeometryOptions{});
    EXPECT_EQ(report["sides"].get<std::vector<int>>(), counts);
    EXPECT_EQ(report["vertices"], patch.mesh.vertices.rows()) << arg;
    EXPECT_EQ(report["faces"], patch.mesh.faces.rows()) << arg;
    EXPECT_EQ(report["distortion"], patch.quality.distortion) << arg;
    EXPECT_EQ(report["distortion"], patch.topology.distortion) << arg;
    EXPECT_EQ(report["irregular_vertices"], patch.quality.irregular_vertices) << arg;
    EXPECT_EQ(report["partition"], patch.topology.partition) << arg;
    EXPECT_EQ(report["valid"], meshing::validate(patch.mesh).ok()) << arg;
    EXPECT_TRUE(report["valid"].get<bool>()) << arg;
    // JSON doubles round-trip exactly (17 significant digits).
    EXPECT_DOUBLE_EQ(report["min_angle_deg"].get<double>(), patch.quality.min_angle_deg) << arg;
    EXPECT_DOUBLE_EQ(report["max_angle_deg"].get<double>(), patch.quality.max_angle_deg) << arg;
    EXPECT_DOUBLE_EQ(report["scaled_jacobian_min"].get<double>(), patch.quality.scaled_jacobian_min)
        << arg;
    EXPECT_EQ(report["inverted_quads"], 0) << arg;
  }
}

TEST_F(FillCommand, ObjHasTheReportedFaces) {
  const fs::path obj = dir_ / "patch.obj";
  const CommandResult run = run_sketchdrape("fill --sides 6,4,4,2 --json --obj " + obj.string());
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const nlohmann::json report = nlohmann::json::parse(run.output);
  std::ifstream in(obj);
  ASSERT_TRUE(in) << "no OBJ written";
  int vertices = 0, faces = 0;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::string tag;
    words >> tag;
    if (tag == "v") {
      double x, y, z;
      ASSERT_TRUE(words >> x >> y >> z) << line;
      ++vertices;
    } else if (tag == "f") {
      int index, corners = 0;
      while (words >> index) {
        EXPECT_GE(index, 1);
        EXPECT_LE(index, report["vertices"].get<int>());
        ++corners;
      }
      EXPECT_EQ(corners, 4) << line;
      ++faces;
    }
  }
  EXPECT_EQ(vertices, report["vertices"].get<int>());
  EXPECT_EQ(faces, report["faces"].get<int>());
}

TEST_F(FillCommand, PngIsWritten) {
  const fs::path png = dir_ / "patch.png";
  const CommandResult run =
      run_sketchdrape("fill --sides 5,6,3,6,4 --size 200x150 --png " + png.string());
  ASSERT_EQ(run.exit_code, 0) << run.output;
  std::ifstream in(png, std::ios::binary);
  std::stringstream bytes;
  bytes << in.rdbuf();
  const render::Image image = render::decode_png(bytes.str());
  EXPECT_EQ(image.width, 200);
  EXPECT_EQ(image.height, 150);
  // Not blank: the patch and its edges differ from the background.
  bool varied = false;
  for (size_t i = 4; i < image.rgba.size() && !varied; i += 4)
    varied = image.rgba[i] != image.rgba[0];
  EXPECT_TRUE(varied);
}

TEST_F(FillCommand, BadSidesExitTwoWithASentenceAndWriteNothing) {
  for (const std::string sides : {"--sides 3,3,3", "--sides 0,2", "--sides a,b", ""}) {
    const fs::path obj = dir_ / "bad.obj", png = dir_ / "bad.png";
    const CommandResult run =
        run_sketchdrape("fill " + sides + " --obj " + obj.string() + " --png " + png.string());
    EXPECT_EQ(run.exit_code, 2) << sides << ": " << run.output;
    EXPECT_GT(run.output.size(), 20u) << sides;  // a sentence, not a bare code
    EXPECT_FALSE(fs::exists(obj)) << sides;
    EXPECT_FALSE(fs::exists(png)) << sides;
  }
  EXPECT_NE(run_sketchdrape("fill --sides 3,3,3").output.find("even"), std::string::npos);
  EXPECT_NE(run_sketchdrape("fill --sides 0,2").output.find("at least 1 edge"), std::string::npos);
  EXPECT_NE(run_sketchdrape("fill --sides a,b").output.find("not a whole number"),
            std::string::npos);
  EXPECT_NE(run_sketchdrape("fill").output.find("--sides"), std::string::npos);
}

}  // namespace
}  // namespace sd::test
