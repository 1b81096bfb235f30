#pragma once
// Strong index types for the 4-8 mesh: a VertexId cannot be passed where a TriangleId is meant.

#include <compare>
#include <cstddef>
#include <functional>

namespace sd::meshing {

// An index into one of Mesh48's slot arrays; default-constructed ids are invalid (-1).
template <class Tag>
class StrongId {
 public:
  constexpr StrongId() = default;
  constexpr explicit StrongId(int value) : value_(value) {}

  constexpr int value() const { return value_; }
  constexpr bool valid() const { return value_ >= 0; }
  constexpr auto operator<=>(const StrongId&) const = default;

 private:
  int value_ = -1;
};

using VertexId = StrongId<struct VertexTag>;
using TriangleId = StrongId<struct TriangleTag>;
using BlockId = StrongId<struct BlockTag>;

}  // namespace sd::meshing

template <class Tag>
struct std::hash<sd::meshing::StrongId<Tag>> {
  std::size_t operator()(const sd::meshing::StrongId<Tag>& id) const noexcept {
    return std::hash<int>{}(id.value());
  }
};
