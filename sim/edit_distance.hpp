#pragma once
// The Levenshtein distance between two words, for the "did you mean" of a misspelt key or name:
// the fabric reader here and the sketch reader (scene/) both offer the nearest known word. Inline,
// so that the scene layer's fuzz targets, built without sim's .cpp files, can use it.

#include <algorithm>
#include <cstddef>
#include <string_view>
#include <vector>

namespace sd::sim {

inline size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diagonal = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

}  // namespace sd::sim
