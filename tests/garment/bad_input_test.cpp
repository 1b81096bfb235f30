// The bad-input suite (tests/garment/bad/): each file must fail with a SketchError naming the
// file, the JSON path in expected.tsv and containing the expected fragment.

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "garment/body_surface.hpp"
#include "garment/garment_mesh.hpp"
#include "garment/sketch_file.hpp"
#include "garment/sketch_inputs.hpp"
#include "tests/garment/bad_cases.hpp"

namespace sd::garment {
namespace {

TEST(BadInput, EveryFileFailsWithPathAndSentence) {
  const auto cases = test::bad_cases();
  ASSERT_GE(cases.size(), 11u);
  // Every bad file has a line in the table.
  size_t files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(cases.front().file.parent_path()))
    files += entry.path().extension() == ".json" ? 1 : 0;
  EXPECT_EQ(files, cases.size());
  for (const test::BadCase& c : cases) {
    try {
      const Sketch sketch = load_sketch(c.file);
      const Body body = load_sketch_body(sketch);
      const BodySurface surface(body.mesh);
      build_garment(sketch, surface);
      ADD_FAILURE() << c.file << " was accepted";
    } catch (const SketchError& e) {
      EXPECT_EQ(e.file(), c.file.string());
      EXPECT_EQ(e.json_path(), c.json_path) << e.what();
      EXPECT_NE(std::string(e.what()).find(c.fragment), std::string::npos)
          << e.what() << "\n  expected: " << c.fragment;
    }
  }
}

}  // namespace
}  // namespace sd::garment
