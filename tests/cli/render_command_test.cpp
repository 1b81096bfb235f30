// `sketchdrape render`: outputs appear together or not at all, bad input exits with 2.

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>

#include "garment/body.hpp"
#include "src/render/image.hpp"
#include "tests/cli/run_command.hpp"

namespace sd::test {
namespace {

namespace fs = std::filesystem;

class RenderCommand : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("sd_render_cli_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  static render::Image read_png(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream bytes;
    bytes << in.rdbuf();
    return render::decode_png(bytes.str());
  }
  static size_t file_count(const fs::path& dir) {
    if (!fs::exists(dir)) return 0;
    return static_cast<size_t>(
        std::distance(fs::recursive_directory_iterator(dir), fs::recursive_directory_iterator()));
  }

  fs::path dir_;
};

TEST_F(RenderCommand, WritesOnePngPerViewIntoADirectory) {
  const fs::path out = dir_ / "views";
  const CommandResult r = run_sketchdrape(
      "render builtin --view front --view three-quarter "
      "--view left --size 90x120 -o " +
      out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* view : {"front", "three-quarter", "left"}) {
    const render::Image image = read_png(out / (std::string(view) + ".png"));
    EXPECT_EQ(image.width, 90);
    EXPECT_EQ(image.height, 120);
  }
  EXPECT_EQ(file_count(out), 3u);                            // no temporary files left
  EXPECT_NE(r.output.find("front.png"), std::string::npos);  // paths printed
}

TEST_F(RenderCommand, APngOutputNamesTheFileForOneView) {
  const fs::path out = dir_ / "one.png";
  const CommandResult r =
      run_sketchdrape("render builtin --view back --size 40x60 -o " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(read_png(out).width, 40);
  // Several views cannot go to one file: usage error, nothing written.
  const fs::path two = dir_ / "two.png";
  const CommandResult bad =
      run_sketchdrape("render builtin --view front --view back -o " + two.string());
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_FALSE(fs::exists(two));
}

TEST_F(RenderCommand, BadViewExitsTwoAndLeavesNothing) {
  const fs::path out = dir_ / "bad";
  // A good view first: it must not be written either.
  const CommandResult r =
      run_sketchdrape("render builtin --view front --view sideways -o " + out.string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("unknown view 'sideways'"), std::string::npos) << r.output;
  EXPECT_EQ(file_count(out), 0u);
  EXPECT_EQ(file_count(dir_), 0u);
}

TEST_F(RenderCommand, BadSizeOrMissingFileExitsTwo) {
  const fs::path out = dir_ / "bad";
  for (const char* size : {"800", "0x100", "axb", "100x99999"}) {
    const CommandResult r =
        run_sketchdrape(std::string("render builtin --size ") + size + " -o " + out.string());
    EXPECT_EQ(r.exit_code, 2) << size << ": " << r.output;
    EXPECT_NE(r.output.find("WIDTHxHEIGHT"), std::string::npos) << r.output;
  }
  const CommandResult missing = run_sketchdrape("render /nonexistent/body.obj -o " + out.string());
  EXPECT_EQ(missing.exit_code, 2) << missing.output;
  const CommandResult missing_garment =
      run_sketchdrape("render /nonexistent/skirt.obj --body builtin -o " + out.string());
  EXPECT_EQ(missing_garment.exit_code, 2) << missing_garment.output;
  EXPECT_NE(missing_garment.output.find("does not exist"), std::string::npos);
  const CommandResult no_output = run_sketchdrape("render builtin");
  EXPECT_EQ(no_output.exit_code, 2);
  EXPECT_EQ(file_count(dir_), 0u);
}

// Trial 43, P12: a body file that breaks its up axis's facing convention (Y up, facing +x
// instead of +z) has landmarks only when read with --facing; `render` had no --facing (nor
// --up, --height, --scale), so `render --landmarks` could not draw it, and its error sent the
// user to `info --facing`. The built-in body turned a quarter round, in centimetres.
TEST_F(RenderCommand, DrawsLandmarksOfABodyReadWithTheOptionsInfoTakes) {
  const meshing::TriMesh body = garment::load_body("builtin").mesh;  // m, +y up, facing +z
  const fs::path obj = dir_ / "turned.obj";
  {
    std::ofstream out(obj);
    for (Eigen::Index v = 0; v < body.vertices.rows(); ++v)  // (x, y, z) -> (z, y, -x): faces +x
      out << "v " << 100 * body.vertices(v, 2) << " " << 100 * body.vertices(v, 1) << " "
          << -100 * body.vertices(v, 0) << "\n";
    for (Eigen::Index f = 0; f < body.faces.rows(); ++f)
      out << "f " << body.faces(f, 0) + 1 << " " << body.faces(f, 1) + 1 << " "
          << body.faces(f, 2) + 1 << "\n";
  }
  const CommandResult plain = run_sketchdrape(
      "render " + obj.string() + " --landmarks --size 40x60 -o " + (dir_ / "plain.png").string());
  EXPECT_NE(plain.exit_code, 0) << plain.output;  // 1: no landmarks is not a usage error
  EXPECT_NE(plain.output.find("looks turned"), std::string::npos) << plain.output;
  EXPECT_NE(plain.output.find("`render --facing`"), std::string::npos) << plain.output;
  const fs::path png = dir_ / "landmarks.png";
  const CommandResult r =
      run_sketchdrape("render " + obj.string() + " --up +y --facing +x --height 1.6 --landmarks " +
                      "--size 40x60 -o " + png.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(read_png(png).size(), (render::ImageSize{40, 60}));
  // `info` takes the same option set (one definition, cli.hpp's add_body_file_options).
  const CommandResult info = run_sketchdrape("info " + obj.string() + " --facing +x --json");
  EXPECT_EQ(info.exit_code, 0) << info.output;
}

// A garment file in the body's frame: a tube around the hips with two groups (panels).
TEST_F(RenderCommand, DrawsAGarmentOverABody) {
  const fs::path obj = dir_ / "tube.obj";
  {
    std::ofstream out(obj);
    const int segments = 24;
    for (int ring = 0; ring < 2; ++ring)
      for (int s = 0; s < segments; ++s) {
        const double phi = 2 * std::numbers::pi * s / segments;
        out << "v " << 0.22 * std::cos(phi) << " " << (ring ? 0.75 : 1.0) << " "
            << 0.22 * std::sin(phi) << "\n";
      }
    for (int half = 0; half < 2; ++half) {
      out << "g " << (half ? "back" : "front") << "\n";
      for (int s = half * segments / 2; s < (half + 1) * segments / 2; ++s) {
        const int a = s + 1, b = (s + 1) % segments + 1;  // OBJ indices are 1-based
        out << "f " << a << " " << b << " " << b + segments << " " << a + segments << "\n";
      }
    }
  }
  const fs::path out = dir_ / "dressed";
  const CommandResult r = run_sketchdrape("render " + obj.string() +
                                          " --body builtin --wireframe --view front --view back "
                                          "--size 80x120 -o " +
                                          out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const render::Image front = read_png(out / "front.png");
  const render::Image back = read_png(out / "back.png");
  EXPECT_EQ(front.size(), (render::ImageSize{80, 120}));
  EXPECT_NE(front.rgba, back.rgba);
}

TEST_F(RenderCommand, ExplicitCamera) {
  const fs::path out = dir_ / "cam";
  const CommandResult r = run_sketchdrape(
      "render builtin --eye 0,1.6,3 --target 0,1.5,0 --fov 20 --size 50x50 -o " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(fs::exists(out / "custom.png"));
  const CommandResult bad =
      run_sketchdrape("render builtin --eye 0,1,0 --target 0,1,0 -o " + (dir_ / "cam2").string());
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
}

}  // namespace
}  // namespace sd::test
