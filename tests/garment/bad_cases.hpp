#pragma once
// Reads tests/garment/bad/expected.tsv: one bad sketch file per line with the JSON path and a
// fragment its error message must contain.

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace sd::test {

struct BadCase {
  std::filesystem::path file;
  std::string json_path;
  std::string fragment;
};

inline std::vector<BadCase> bad_cases() {
  const std::filesystem::path dir = std::filesystem::path(SD_SOURCE_DIR) / "tests/garment/bad";
  std::ifstream in(dir / "expected.tsv");
  std::vector<BadCase> cases;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ls(line);
    BadCase c;
    std::string name;
    std::getline(ls, name, '\t');
    std::getline(ls, c.json_path, '\t');
    std::getline(ls, c.fragment);
    c.file = dir / name;
    cases.push_back(c);
  }
  return cases;
}

}  // namespace sd::test
