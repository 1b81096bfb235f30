// The meshing regression corpus (data/meshing/corpus.json): every case is filled and its
// distortion and irregular vertex count compared with the stored figures. Worse fails; better
// is reported, and the file must then be updated:
//     SD_UPDATE_MESHING_CORPUS=1 ./meshing_tests --gtest_filter='MeshingCorpus.*'
// rewrites the stored figures with the current ones (docs/meshing.md).

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "meshing/patch_fill.hpp"
#include "tests/meshing/layout_family.hpp"
#include "tests/meshing/patch_fill_checks.hpp"

namespace sd::meshing {
namespace {

const char* const kCorpusPath = SD_SOURCE_DIR "/data/meshing/corpus.json";

TEST(MeshingCorpus, NoCaseGetsWorse) {
  std::ifstream in(kCorpusPath);
  ASSERT_TRUE(in) << "cannot read " << kCorpusPath;
  nlohmann::json corpus = nlohmann::json::parse(in);
  const bool update = std::getenv("SD_UPDATE_MESHING_CORPUS") != nullptr;
  ASSERT_GE(corpus["cases"].size(), 200u);
  int improved = 0, unchanged = 0, missing = 0;
  int proven = 0;
  for (auto& entry : corpus["cases"]) {
    const std::string name = entry["name"];
    const auto counts = entry["sides"].get<std::vector<int>>();
    const auto n = static_cast<int>(counts.size());
    PatchTopology topo;
    if (entry.contains("reflex_corner_deg")) {
      // A notched region filled in 3D: never an inverted quad.
      FilledPatch patch = fill_region(test::notched_sides(counts, entry["reflex_corner_deg"]));
      EXPECT_TRUE(validate(patch.mesh).ok()) << name;
      EXPECT_EQ(patch.quality.inverted_quads, 0) << name << " " << test::describe(counts);
      topo = std::move(patch.topology);
      topo.distortion = patch.quality.distortion;
      topo.irregular_vertices = patch.quality.irregular_vertices;
    } else {
      topo = fill_region(counts);
      EXPECT_TRUE(test::well_formed(topo, counts)) << name;
      // The proven minimum: |n − 4| when reached; for n <= 5, |n − 4| + 2 when the layout
      // family, complete at |n − 4| there, has nothing that cheap (docs/meshing.md).
      const int bound = std::abs(n - 4);
      std::optional<int> minimum;
      if (topo.distortion == bound)
        minimum = bound;
      else if (topo.distortion == bound + 2 && n <= 5 && !test::family_reaches(counts, bound))
        minimum = bound + 2;
      else if (n <= 5 && topo.distortion > bound + 2 && test::family_reaches(counts, bound + 2))
        ADD_FAILURE() << name << " " << test::describe(counts) << ": the layout family reaches "
                      << bound + 2 << ", the fill " << topo.distortion;
      if (minimum) ++proven;
      if (entry.contains("minimum")) {
        EXPECT_EQ(minimum.value_or(-1), entry["minimum"].get<int>()) << name << ": proof changed";
        EXPECT_EQ(topo.distortion, entry["minimum"].get<int>())
            << name << " " << test::describe(counts) << " misses its proven minimum";
      } else if (minimum && !update) {
        ADD_FAILURE() << name << " has a proven minimum " << *minimum
                      << " the corpus does not record: update it";
      }
      if (update && minimum) entry["minimum"] = *minimum;
    }
    if (!entry.contains("distortion")) {
      ++missing;
    } else {
      const int distortion = entry["distortion"], irregular = entry["irregular_vertices"];
      const auto now = std::pair(topo.distortion, topo.irregular_vertices);
      const auto then = std::pair(distortion, irregular);
      if (now > then && !update) {
        ADD_FAILURE() << name << " " << test::describe(counts) << " got worse: distortion "
                      << distortion << " -> " << topo.distortion << ", irregular vertices "
                      << irregular << " -> " << topo.irregular_vertices;
      } else if (now < then) {
        ++improved;
        std::cout << "improved: " << name << " " << test::describe(counts) << " distortion "
                  << distortion << " -> " << topo.distortion << ", irregular vertices " << irregular
                  << " -> " << topo.irregular_vertices << "\n";
      } else {
        ++unchanged;
      }
    }
    if (update) {
      entry["distortion"] = topo.distortion;
      entry["irregular_vertices"] = topo.irregular_vertices;
      entry["partition"] = topo.partition;
    }
  }
  std::cout << corpus["cases"].size() << " cases: " << unchanged << " unchanged, " << improved
            << " improved, " << missing << " without expectations, " << proven
            << " with a proven minimum\n";
  if (update) {
    std::ostringstream out;  // one case per line, so that diffs show which figures changed
    out << "{\"format\": " << corpus["format"].dump() << ",\n \"cases\": [\n";
    for (size_t i = 0; i < corpus["cases"].size(); ++i)
      out << "  " << corpus["cases"][i].dump() << (i + 1 < corpus["cases"].size() ? ",\n" : "\n");
    out << " ]\n}\n";
    std::ofstream(kCorpusPath) << out.str();
    std::cout << "rewrote " << kCorpusPath << "\n";
  } else {
    EXPECT_EQ(missing, 0) << "cases without expected figures: run with SD_UPDATE_MESHING_CORPUS=1";
    if (improved > 0)
      std::cout << improved
                << " case(s) improved: update the corpus with "
                   "SD_UPDATE_MESHING_CORPUS=1 so that they cannot regress\n";
  }
}

}  // namespace
}  // namespace sd::meshing
