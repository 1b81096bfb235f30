#pragma once
// Private to sim/cloth_model.cpp and sim/bend_elements.cpp: the makers of the bend elements
// (hinges, bend stencils, quadratic vertex bends) that build_cloth_model and update_cloth_model
// share. Not part of the library's interface.

#include <Eigen/Core>
#include <array>
#include <vector>

#include "sim/cloth_model.hpp"

namespace sd::sim::detail {

// The hinge on the edge that starts at corner `first_corner` of triangle `first` (the one of
// the two with the lower row); `second_corner` is where the edge starts in `second`.
// `areas`: the sum of the two triangles' unscaled rest areas.
HingeElement make_hinge(const Eigen::MatrixX3d& rest, const std::array<int, 3>& first,
                        int first_corner, const std::array<int, 3>& second, int second_corner,
                        double areas, const ClothModelOptions& options);

// Scales each hinge's weight |e|²/(A1+A2) by the share of its response that comes from bends
// across its edge (see bend_elements.cpp).
void calibrate_hinge_weights(const Eigen::MatrixX3d& rest, std::vector<HingeElement>& hinges);

// The bend stencils of every vertex whose one-ring has more points than the smooth shapes
// constrain (see BendStencil).
std::vector<BendStencil> make_bend_stencils(const Eigen::MatrixX3d& rest,
                                            const Eigen::MatrixX3i& faces);

// The quadratic bending elements of every vertex that has a triangle (VertexBendElement), in
// vertex order; with `wanted` (#V, empty: all) only those of the vertices with wanted[v], each
// the same bits as in the whole set (update_cloth_model makes the changed ones this way).
std::vector<VertexBendElement> make_vertex_bends(const Eigen::MatrixX3d& rest,
                                                 const Eigen::MatrixX3i& faces,
                                                 BendRestShape bend_rest,
                                                 const std::vector<char>& wanted = {});

}  // namespace sd::sim::detail
