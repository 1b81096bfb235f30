#pragma once
// Private to meshing/mesh48*.cpp: the helpers the construction, the topology changes and the
// validation of Mesh48 share. Not part of the library's interface.

#include <string>
#include <utility>
#include <vector>

#include "meshing/check.hpp"
#include "meshing/mesh48.hpp"

namespace sd::meshing::detail {

// Debug builds check every invariant of the mesh after each factory and each split or merge.
inline void debug_validate([[maybe_unused]] const Mesh48& m, [[maybe_unused]] const char* after) {
#ifndef NDEBUG
  const std::vector<std::string> problems = m.validate();
  SD_DCHECK(problems.empty(), std::string("after ") + after + ": " + problems.front());
#endif
}

inline std::string edge_name(int u, int v) {
  return std::to_string(u) + "-" + std::to_string(v);
}

// Directed edges of a triangle list grouped by their start vertex (compressed rows), so that an
// edge's reverse is found in O(valence) without sorting.
class HalfEdgeIndex {
 public:
  struct Entry {
    int to;
    int face;
    int corner;  // local index of the face's vertex opposite the edge
  };

  // corner_vertex(f, k): vertex k of face f, for 0 <= f < face_count, in 0..vertex_count-1.
  template <class CornerVertex>
  HalfEdgeIndex(int vertex_count, int face_count, CornerVertex corner_vertex)
      : start_(static_cast<std::size_t>(vertex_count) + 1, 0),
        entries_(3 * static_cast<std::size_t>(face_count)) {
    for (int f = 0; f < face_count; ++f)
      for (int k = 0; k < 3; ++k) ++start_[corner_vertex(f, (k + 1) % 3) + 1];
    for (int v = 0; v < vertex_count; ++v) start_[v + 1] += start_[v];
    std::vector<int> fill(start_.begin(), start_.end() - 1);
    for (int f = 0; f < face_count; ++f)
      for (int k = 0; k < 3; ++k)
        entries_[fill[corner_vertex(f, (k + 1) % 3)]++] = {corner_vertex(f, (k + 2) % 3), f, k};
  }

  int vertex_count() const { return static_cast<int>(start_.size()) - 1; }
  int out_degree(int v) const { return start_[v + 1] - start_[v]; }
  const Entry* begin(int v) const { return entries_.data() + start_[v]; }
  const Entry* end(int v) const { return entries_.data() + start_[v + 1]; }
  const Entry* find(int from, int to) const {
    for (const Entry* e = begin(from); e != end(from); ++e)
      if (e->to == to) return e;
    return nullptr;
  }
  // A directed edge listed twice (inconsistent orientation or a non-manifold edge), else
  // {-1, -1}.
  std::pair<int, int> duplicate() const {
    for (int v = 0; v < vertex_count(); ++v)
      for (const Entry* e = begin(v); e != end(v); ++e)
        for (const Entry* g = e + 1; g != end(v); ++g)
          if (e->to == g->to) return {v, e->to};
    return {-1, -1};
  }

 private:
  std::vector<int> start_;
  std::vector<Entry> entries_;
};

inline const char* const kDuplicateEdgeText =
    " is traversed in the same direction by two faces: the faces are not consistently "
    "oriented or the edge is shared by more than two faces";

}  // namespace sd::meshing::detail
