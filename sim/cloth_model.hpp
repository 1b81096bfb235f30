#pragma once
// The per-element data of the cloth on a fixed mesh: rest (material) frames of the triangles,
// bending hinges, lumped masses, and the sparsity pattern of the 3n-by-3n system matrix.
// Building it is cheap (linear in the mesh size), so the adaptive mesh can rebuild it after
// every topology change.

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <algorithm>
#include <array>
#include <optional>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "sim/diamond_membrane.hpp"
#include "sim/fabric.hpp"

namespace sd::sim {

// A cloth mesh the simulator cannot use (degenerate rest triangle, index out of range, bad
// warp direction). Message says which element and why.
class InvalidClothError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// Plain input data: the simulator never sees the garment types.
struct ClothInput {
  Eigen::MatrixX3d rest_positions;  // #V by 3, the designed shape, metres
  Eigen::MatrixX3i triangles;       // #F by 3 vertex indices
  // #F by 3 warp direction per triangle (projected into the triangle's plane and normalised),
  // or empty: warp is then the in-plane direction closest to `up` (weft = normal × warp).
  Eigen::MatrixX3d warp;
  Eigen::Vector3d up = Eigen::Vector3d::UnitY();
  // #F by 6 rest (material) coordinates (u0 v0 u1 v1 u2 v2, metres; u along warp, v along weft,
  // counter-clockwise), or empty: each triangle's shape in rest_positions. A flat pattern piece's
  // triangles, which no 3D rest shape can hold (seam vertices have one position per piece).
  // The warp directions are then not used for stretch and shear.
  Eigen::MatrixXd rest_uv;
  // #F by 2 widths (warp, weft; metres, positive) whose Euler load caps each triangle's
  // compression under Compression::buckling, or empty: each triangle's own rest extent (what
  // rest_widths gives). A refined triangle is given its level-0 ancestor's, so that a split
  // keeps the cap N* = π²B/l² and with it the energy of a buckled region (docs/adaptive.md,
  // "A gathered panel that never rests").
  Eigen::MatrixX2d buckling_width;
};

enum class BendRestShape {
  designed,  // rest dihedral angle of each hinge taken from the rest positions
  flat,      // every rest angle zero
};

// How the hinges' bending weights are set (docs/simulator.md, "Bending on any mesh").
enum class BendWeights {
  // |e|²/(A1+A2)·a_nn²/(a_nn² + a_tt² + a_nt²/2): on the 4-8 mesh every smooth bend then
  // costs the continuum energy ½·B·tr(K²), in any direction and either orientation.
  calibrated,
  edge,  // |e|²/(A1+A2): exact for a bend across the edge only
};

// Which discrete bending energy the cloth uses (docs/simulator.md, "Bending on any mesh").
enum class BendModel {
  // Per vertex ½·B·|L̃x − c·N(x)|²/A_v: the cotangent Laplacian of the positions, completed at
  // free boundaries by the boundary's own flux, against the rest curvature (VertexBendElement;
  // the quadratic isometric bending of Bergou et al. 2006). Consistent on any triangulation:
  // ½·B·∫(κ1 + κ2)² dA, which for isometric bending is ½·B·∫tr K² dA.
  quadratic,
  // Per interior edge ½·B·weight·(θ − θ0)² (discrete shells), with the weights and stencils
  // below: on the 4-8 mesh too soft and orientation-dependent.
  hinges,
};

// How the membrane answers compression along warp or weft (docs/simulator.md, "Compression and
// buckling"). Tension is the same in both.
enum class Compression {
  // ½·K·A·ε² in compression as in tension: the fabric resists compression with its tensile
  // stiffness, which real fabric never does (it buckles out of its plane at almost no load).
  linear,
  // Choi & Ko's (2002) post-buckling response: along a direction the compressive force per
  // width stops growing at the Euler load N* = π²·B / l² of the triangle's width l along
  // that direction (its own, or ClothInput::buckling_width: on the adaptive mesh its level-0
  // ancestor's), the largest load an element of that length carries before it would buckle
  // out of its plane. Beyond the buckling strain ε* = N*/K the energy grows linearly, A·N*
  // per unit strain: the triangle shortens as a strip that has buckled below the mesh's
  // resolution. As l → 0 the cap N* grows as 1/l², so the response converges to linear.
  // Where shear compresses a bias beyond its Euler load the bias wrinkles the same way
  // (sim/forces.cpp, bias_wrinkle); tension and shear under tension are unchanged.
  buckling,
};

std::string_view compression_name(Compression compression);
std::optional<Compression> parse_compression(std::string_view name);

// The bend model's name in sketch files ("quadratic", "hinges") and the model from it.
std::string_view bend_model_name(BendModel model);
std::optional<BendModel> parse_bend_model(std::string_view name);

struct ClothModelOptions {
  BendRestShape bend_rest = BendRestShape::designed;
  BendModel bend_model = BendModel::quadratic;
  Compression compression = Compression::linear;
  BendWeights bend_weights = BendWeights::edge;
  // Stiffness of the bend stencils relative to the fabric's B (0: none); see BendStencil.
  // Off by default: they hold the 4-8 mesh's sublattice mode only away from the boundary
  // (docs/simulator.md, "Bending on any mesh"). Built from the unscaled rest shape (a panel's
  // ease does not rescale them).
  double bend_stencil_stiffness = 0.0;
  // Whether clamp_bending also reads the pinned points behind a clamp's edge in the free
  // vertices' rows as ghosts (the even extension of the free side; docs/simulator.md, "Ghost
  // points at a clamp"). Off by default: alone it stiffens the 4-8 mesh at 45° into its membrane
  // locking (silk's Peirce chord 39.7°), which diamond_membrane removes, and that is not yet
  // stable in dynamic runs.
  bool clamp_ghost_points = false;
  // Whether the membrane of each diamond of the 4-8 mesh (DiamondElement) is evaluated with its
  // centre moved to where a smooth bend puts it (docs/simulator.md, "The diamond membrane"):
  // removes the 4-8 mesh's membrane locking at 45°; flat cloth is unchanged; a dent of the centre
  // is charged as any vertex's (the heights are measured from the centre its corners and their
  // neighbours predict). Off by default (docs/simulator.md, "The predicted centre").
  bool diamond_membrane = false;
};

// Row-major 3n-by-3n matrix, the layout the system matrix and the Jacobians share.
using SparseMatrixR = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;

// One triangle: w_u = Σ_k du[k]·x_k and w_v = Σ_k dv[k]·x_k are the deformation gradient's
// columns along warp and weft (Baraff & Witkin 1998, eq. 9), so |w_u| = 1 means unstretched.
struct TriangleElement {
  std::array<int, 3> vertices{};
  double rest_area = 0.0;  // m²
  Eigen::Vector3d du = Eigen::Vector3d::Zero();
  Eigen::Vector3d dv = Eigen::Vector3d::Zero();
  std::array<int, 9> blocks{};  // offset of block (a,b) in the matrix row, see BlockPattern
  // m, the rest triangle's extent along the warp and the weft, or ClothInput::buckling_width
  // (the widths of the Euler load of Compression::buckling)
  double width_u = 0.0;
  double width_v = 0.0;
};

// One interior edge (x0,x1) with opposite vertices x2 (first triangle) and x3 (second).
struct HingeElement {
  std::array<int, 4> vertices{};
  double rest_angle = 0.0;  // rad, in (−π, π]
  double weight = 0.0;      // |e|²/(A1+A2) in the rest shape (or calibrated), dimensionless
  std::array<int, 16> blocks{};
};

// A vertex and its one-ring, with the combinations of their positions that vanish for every
// smooth (quadratic) shape of the rest surface around the vertex: they measure only the
// grid-scale zigzag that hinge angles cannot see (on the 4-8 mesh, the two kinds of vertices
// moving against each other). Energy ½·k·B·Σ_jl coupling(j,l)·x_j·x_l with
// coupling = A_v·RᵀR (R: the combinations, rows orthonormal, scaled by 1/ρ², ρ the one-ring's
// rms radius; A_v the vertex's area), zero at the rest shape and for any rigid motion.
struct BendStencil {
  std::vector<int> vertices;  // sorted, the centre among them
  Eigen::MatrixXd coupling;   // #vertices square, 1/m², symmetric positive semi-definite
  std::vector<int> blocks;    // #vertices², offset of block (j,l), see BlockPattern
};

// The bending element of one vertex v for BendModel::quadratic: three curvature vectors
// r_k(x) = Σ_j rows(k, j)·x_j − rest_normal(k)·N(x) and the energy
// ½·B·inverse_area·(½|r_0|² + ½|r_1|² + 2|r_2|²), which for r_0 ≈ A_v·Δx, r_1 ≈ A_v·(x_uu − x_vv)
// and r_2 ≈ A_v·x_uv (u, v rest tangent coordinates) is ½·B·A_v·(|x_uu|² + 2|x_uv|² + |x_vv|²):
// ½·B·tr K²·A_v for isometric bending, the continuum energy of a plate with Poisson ratio 0,
// in every direction. (Δx alone, the quadratic model of Bergou et al. 2006, is ν = 1: a narrow
// strip bends almost for free into a saddle.) Every row is zero for an affine map of a flat rest
// and exact for quadratic shapes, up to free edges (docs/simulator.md, "Bending on any mesh").
// N(x) = ½·Σ_fan (x_b − x_v)×(x_c − x_v) is the area vector of the vertex's triangles;
// rest_normal·N(x̄) is the rest shape's curvature vector, so a shaped panel is at rest in its
// designed shape and the target turns with the surface. Flat rest: rest_normal = 0, the r_k are
// linear and the energy quadratic (constant Hessian).
struct VertexBendElement {
  std::vector<int> vertices;                      // sorted, the centre among them
  int centre = 0;                                 // index of v in `vertices`
  Eigen::Matrix<double, 3, Eigen::Dynamic> rows;  // 3 × #vertices, m² per m² of curvature
  double inverse_area = 0.0;  // 1/A_v (the mixed Voronoi area of Meyer et al. 2003), 1/m²
  Eigen::Vector3d rest_normal = Eigen::Vector3d::Zero();  // 1/m
  std::vector<std::array<int, 2>> fan;  // (b, c) indices into `vertices` of each triangle
                                        // (v, b, c); only when rest_normal != 0
  std::vector<int> blocks;              // #vertices², offset of block (j,l), see BlockPattern
  bool clamped = false;                 // inverse_area doubled by clamp_bending
  bool ghosted = false;                 // rows read pinned points as ghosts (clamp_bending)
};

// Structurally symmetric block sparsity: rows 3i..3i+2 all hold the columns of the vertices
// adjacent to i (itself included), in increasing order. Block (i,j), entry (a,b) is at value
// index outer[3i+a] + offset(i,j) + b, where offset(i,j) is what the elements store.
struct BlockPattern {
  SparseMatrixR zero_matrix;          // the pattern with all values zero
  std::vector<int> diagonal_offsets;  // offset(i,i), #V
};

// The flat-rest vertex bends (an empty fan: rest_normal = 0) gathered into constant sparse
// operators. Their rows r = R x (R: each bend's three rows over its vertices, every coordinate
// alike) give the energy ½·B·Σ w r² and the force −B·Rᵀ W (r + β ṙ) with W the bends' weights
// inverse_area·(½, ½, 2), as the elements compute them (the energy as squares, so a rigid motion
// costs nothing to rounding); the Jacobian is constant, K = Rᵀ W R by vertex on the pattern's
// blocks, for its product −B·K u and matrix blocks. One pass over these arrays replaces every
// element's dense products (a sheet's bending was a fifth of its drape; docs/benchmarks.md,
// "Sixth round"). Built by build_cloth_model, update_cloth_model and clamp_bending (the only
// places that make or change vertex bends); `elements` says how many vertex bends it was built
// from, so a model whose bends were changed otherwise falls back to the elements.
struct FlatBendOperator {
  // R by bend row: entries [row_start[r], row_start[r+1]) of row_vertex / row_value.
  std::vector<int> row_start, row_vertex;
  std::vector<double> row_value;   // the rows' weights (dimensionless, m² per m² of curvature)
  std::vector<double> row_weight;  // inverse_area·s_k, 1/m²
  // Rᵀ by vertex: entries [vertex_start[i], vertex_start[i+1]) of vertex_row / vertex_value.
  std::vector<int> vertex_start, vertex_row;
  std::vector<double> vertex_value;
  // K by vertex (columns increasing): entries [k_start[i], k_start[i+1]).
  std::vector<int> k_start, k_column, k_offset;  // k_offset: offset(i, column) of BlockPattern
  std::vector<double> k_value;                   // K_ij, 1/m²
  std::vector<int> curved;                       // the vertex bends left out (curved rest)
  std::size_t elements = 0;                      // vertex_bends.size() when built
};

struct ClothModel {
  int vertex_count = 0;
  FabricParameters fabric;
  std::vector<TriangleElement> triangles;
  std::vector<HingeElement> hinges;  // built for both bend models, used by BendModel::hinges
  BendModel bend_model = BendModel::quadratic;
  BendRestShape bend_rest = BendRestShape::designed;  // what the vertex bends were made for
  Compression compression = Compression::linear;
  std::vector<VertexBendElement> vertex_bends;  // with BendModel::quadratic
  std::vector<BendStencil> stencils;  // with ClothModelOptions::bend_stencil_stiffness > 0
  double bend_stencil_stiffness = 0.0;
  bool clamp_ghost_points = false;  // ClothModelOptions::clamp_ghost_points
  // With ClothModelOptions::diamond_membrane: the diamonds, and the triangles in none of them
  // (whose membrane is evaluated alone). Without, both empty: every triangle alone.
  std::vector<DiamondElement> diamonds;
  std::vector<int> lone_triangles;
  Eigen::VectorXd mass;         // #V lumped masses, kg
  Eigen::VectorXd vertex_area;  // #V rest area attributed to each vertex (a third of each face)
  BlockPattern pattern;
  FlatBendOperator flat_bends;  // with BendModel::quadratic, see FlatBendOperator

  double total_mass() const { return mass.sum(); }
};

// Builds the model. Validates the fabric and the mesh (throws InvalidFabricError or
// InvalidClothError). Non-manifold edges get no hinge (logged as a warning).
ClothModel build_cloth_model(const ClothInput& input, const FabricParameters& fabric,
                             const ClothModelOptions& options = {});

// What a topology change kept of the mesh a model was built for, in the rows of the new mesh.
struct ClothModelReuse {
  std::vector<int> previous_vertex;  // #V: row of the same vertex in the previous mesh, or −1
  // #F: row of the same triangle (same vertices in the same order, same input face) in the
  // previous mesh, or −1 for a triangle the change made.
  std::vector<int> previous_triangle;
};

// The model that build_cloth_model(input, previous.fabric, options) and then
// scale_rest_shapes(scale) (empty: none) would give, element for element and bit for bit, built
// from `previous` (that model of the mesh before the change) where the change did not reach:
// kept triangles and the hinges between two of them are copied with their vertices renumbered,
// and the pattern rows of vertices whose elements are all kept are copied, with their elements'
// offsets; so are the vertex bends (BendModel::quadratic) of the vertices whose faces and
// one-ring's faces the change did not reach. Only the changed neighbourhood is computed and
// sorted. Vertex and triangle
// renumbering must keep the order of what is kept (as Mesh48::compact does); hinges then come in
// the reference's order. Throws InvalidClothError as build_cloth_model, and when `reuse` does
// not describe the input.
ClothModel update_cloth_model(const ClothModel& previous, const ClothModelReuse& reuse,
                              const ClothInput& input, const Eigen::MatrixXd& scale,
                              const ClothModelOptions& options = {});

// Each triangle's own rest extent along its warp and weft (#F by 2, metres): the widths
// build_cloth_model gives its elements when input.buckling_width is empty. Throws
// InvalidClothError as build_cloth_model for a mesh it cannot use.
Eigen::MatrixX2d rest_widths(const ClothInput& input);

// Scales each triangle's rest shape along its warp by a and along its weft by b (a panel's
// `ease`): its rest coordinates (u, v) become (a·u, b·v), so the gradient operators du by 1/a,
// dv by 1/b and the rest area by a·b, and recomputes the lumped masses and vertex areas from the
// scaled areas. `scale` is #triangles by 1 (a = b = e, the isotropic ease) or by 2 (a, b), every
// entry positive. Rest angles, and the bending weights |e|²/(A1+A2), do not change under a
// uniform scale; under an anisotropic one they, and width_u, width_v, keep the unscaled shape's.
void scale_rest_shapes(ClothModel& model, const Eigen::MatrixXd& scale);

// Makes the bending of BendModel::quadratic see the edge of a clamp. Where cloth leaves a clamp
// (a region of pinned vertices held flat) its curvature jumps from 0 to κ0, and the element of a
// vertex on the clamp's edge, whose stencil straddles the edge, measures the average κ0/2 over a
// dual cell of which only half is free cloth: h·(κ0/2)² instead of (h/2)·κ0². The one-sided
// curvature with the clamp's slope is twice the centred one (the ghost-point treatment of a
// clamped beam), over half the area, so those elements carry twice their energy. A clamp-edge
// vertex: pinned, in a triangle whose vertices are all pinned and in one with a free vertex.
// `pinned`: vertex indices. Without it the rigidity near a clamp converges only as O(h).
// With model.clamp_ghost_points and `positions` (3n, the layout the clamp is set up in: pinned
// points where they are held, the free cloth next to them still in its flat layout) the free
// vertices' rows also read the pinned points behind the edge as ghosts, the even extension of
// the free side (ghost_clamped_points in cloth_model.cpp; docs/simulator.md, "Ghost points at a
// clamp").
void clamp_bending(ClothModel& model, const std::vector<int>& pinned,
                   const Eigen::VectorXd* positions = nullptr);

// (Re)builds model.flat_bends from model.vertex_bends and the pattern's offsets.
void build_flat_bend_operator(ClothModel& model);

// Flattens #V by 3 positions into the solver's 3n vector (x0,y0,z0,x1,...) and back.
Eigen::VectorXd flatten_positions(const Eigen::MatrixX3d& positions);
Eigen::MatrixX3d unflatten_positions(const Eigen::VectorXd& flat);

// Offset of block (i, j) in the rows of vertex i (what the elements store), −1 when j is not a
// neighbour of i. A binary search of row 3i.
inline int block_offset(const SparseMatrixR& matrix, int i, int j) {
  const int* begin = matrix.innerIndexPtr() + matrix.outerIndexPtr()[3 * i];
  const int* end = matrix.innerIndexPtr() + matrix.outerIndexPtr()[3 * i + 1];
  const int* found = std::lower_bound(begin, end, 3 * j);
  return found != end && *found == 3 * j ? static_cast<int>(found - begin) : -1;
}

// Value index of entry (a,b) of block `offset` in row-vertex `row_vertex`.
inline int block_value_index(const SparseMatrixR& matrix, int row_vertex, int offset, int a,
                             int b) {
  return matrix.outerIndexPtr()[3 * row_vertex + a] + offset + b;
}

}  // namespace sd::sim
