#pragma once
// A plain quad grid for tests (meshing's own and those of the modules that smooth or unfold
// quad meshes).

#include "meshing/quad_mesh.hpp"

namespace sd::test {

// A w by h grid of unit squares in the z = 0 plane, counter-clockwise seen from +z; vertex
// j·(w + 1) + i is at (i, j, 0).
inline meshing::QuadMesh quad_grid(int w, int h) {
  meshing::QuadMesh mesh;
  mesh.vertices.resize((w + 1) * (h + 1), 3);
  for (int j = 0; j <= h; ++j)
    for (int i = 0; i <= w; ++i) mesh.vertices.row(j * (w + 1) + i) << i, j, 0;
  mesh.faces.resize(w * h, 4);
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      const int v = j * (w + 1) + i;
      mesh.faces.row(j * w + i) << v, v + 1, v + w + 2, v + w + 1;
    }
  return mesh;
}

}  // namespace sd::test
