// The meshing regression corpus (data/meshing/corpus.json): every case is filled and its
// distortion and irregular vertex count compared with the stored figures. Worse fails; better
// is reported, and the file must then be updated:
//     SD_UPDATE_MESHING_CORPUS=1 ./meshing_tests --gtest_filter='MeshingCorpus.*'
// rewrites the stored figures with the current ones (docs/meshing.md).

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "meshing/patch_fill.hpp"
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
  for (auto& entry : corpus["cases"]) {
    const std::string name = entry["name"];
    const auto counts = entry["sides"].get<std::vector<int>>();
    const PatchTopology topo = fill_region(counts);
    EXPECT_TRUE(test::well_formed(topo, counts)) << name;
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
                  << distortion << " -> " << topo.distortion << ", irregular vertices "
                  << irregular << " -> " << topo.irregular_vertices << "\n";
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
            << " improved, " << missing << " without expectations\n";
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
      std::cout << improved << " case(s) improved: update the corpus with "
                   "SD_UPDATE_MESHING_CORPUS=1 so that they cannot regress\n";
  }
}

}  // namespace
}  // namespace sd::meshing
