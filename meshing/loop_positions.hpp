#pragma once
// Positions around a closed loop of boundary vertices, shared by the region partition's layout
// search and its fills (internal to the patch filler).

#include <span>
#include <vector>

namespace sd::meshing::detail {

// i modulo n, in [0, n) for negative i too.
inline int wrap(int i, int n) {
  return ((i % n) + n) % n;
}

// The loop's entries from position `from` to position `to` (inclusive), walking forward.
inline std::vector<int> loop_segment(std::span<const int> loop, int from, int to) {
  const auto size = static_cast<int>(loop.size());
  std::vector<int> out{loop[static_cast<size_t>(from)]};
  for (int p = from; p != to;) {
    p = wrap(p + 1, size);
    out.push_back(loop[static_cast<size_t>(p)]);
  }
  return out;
}

}  // namespace sd::meshing::detail
