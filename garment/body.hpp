#pragma once
// Loading a mannequin (body) mesh from any format assimp reads and normalising it to the
// project's frame: metres, +Y up, facing +Z, feet on y = 0, centred on the vertical axis.

#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "meshing/tri_mesh.hpp"

namespace sd::garment {

// A body file that cannot be used (missing, unreadable, no triangles, non-finite coordinates).
// Derives from std::invalid_argument: it is the user's input that is wrong.
class BodyError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// One of the six axis directions, e.g. "+z" or "-y".
struct AxisDirection {
  int axis = 1;  // 0 = x, 1 = y, 2 = z
  int sign = 1;  // +1 or -1
  std::string name() const;
  // Parses "x", "+y", "-z" (case-insensitive); throws BodyError on anything else.
  static AxisDirection parse(const std::string& text);
};

struct BodyOptions {
  std::optional<AxisDirection> up;  // the file's up axis; inferred when empty
  // The way the figure faces in the file, across `up`; by the up axis's convention when empty.
  std::optional<AxisDirection> facing;
  std::optional<double> scale;   // file units → metres; inferred when empty
  std::optional<double> height;  // target height in metres; wins over scale
  // The body a garment is designed on: a standing figure, however its size is set, so a given
  // `up` along which it lies on its side is refused (a scene's floor or rod is not one).
  bool figure = false;
};

// What the file held before normalisation, and what was done to it.
struct RawBodyInfo {
  std::string source;        // path, or "builtin (<path>)"
  Eigen::Index meshes = 0;   // meshes merged from the scene
  meshing::BoundingBox box;  // in file units and file axes
  AxisDirection up;          // up axis used
  bool up_inferred = true;   // chosen by the rule rather than given
  AxisDirection facing;      // direction the figure faces in the file
  double height = 0;         // extent along up, file units
  double scale = 1;          // applied: metres per file unit
  std::string scale_rule;    // why that scale ("height 1.75 m given", ...)
  // Added after the rotation and the scale (feet on y = 0, centred on the vertical axis), m.
  Eigen::Vector3d shift = Eigen::Vector3d::Zero();
  // Enclosed volume as read, file units³ (negative: faces point inward; meaningful when closed).
  double signed_volume = 0;
  bool flipped_inside_out = false;  // the faces were reversed to point outward
};

struct Body {
  meshing::TriMesh mesh;  // metres, +Y up, facing +Z
  RawBodyInfo raw;
  std::vector<std::string> warnings;  // repairs made while loading
};

// A hole of an open body: a loop (or a chain) of boundary edges, the edges of one triangle only.
struct BodyHole {
  Eigen::Vector3d centre;  // m, the mean of its rim's vertices (in the mesh's frame)
  double across = 0;       // m, the rim's largest extent: how wide the hole is
  int edges = 0;           // boundary edges round it
};

// The holes of `mesh`, largest first: its boundary edges grouped by the vertices they share.
std::vector<BodyHole> body_holes(const meshing::TriMesh& mesh);

// The hole of `holes` whose rim comes within `margin` (m) of `p` (its centre within half its
// width plus the margin), the nearest such; null when none does.
const BodyHole* hole_near(const std::vector<BodyHole>& holes, const Eigen::Vector3d& p,
                          double margin);

// Path of the built-in mannequin: HUMAN.blend from Debian's assimp-testmodels.
std::string builtin_body_path();

// Loads `path` ("builtin" for the built-in mannequin, scaled to 1.75 m unless `options.height`
// says otherwise). Merges all meshes with their node transforms, drops degenerate faces and
// unused vertices (with a warning), then normalises. Throws BodyError on unusable input.
Body load_body(const std::string& path, const BodyOptions& options = {});

// For a body without landmarks: "the figure looks upside down: give "up": "-x"" when its
// landmarks are found once it is turned over (trial 40: an inches body with its head towards -x
// stood on its head by the inferred +x), else "". Costs a landmark search: only on failure.
std::string upside_down_advice(const Body& body);

// Refuses, before assimp reads it, a mesh file whose OFF or PLY header would make assimp reserve
// more memory than the file could fill or read for ever (a PLY header without an end_header
// line, or with numbers or binary bytes in it). `what` opens the message ("body file", "garment
// mesh"). Throws BodyError; files of other formats pass.
void check_mesh_file_header(const std::string& file, const std::string& what);

// Loads another pose of `rest` (the same mesh moved: a frame of an animation exported from the
// same rig) and puts it in the project's frame with exactly the rest body's rotation, scale and
// shift, so that a pose where the arms are raised is not re-centred. Throws BodyError when the
// file cannot be read or its triangles are not the rest body's.
meshing::TriMesh load_body_pose(const std::string& path, const Body& rest);

}  // namespace sd::garment
