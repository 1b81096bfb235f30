#include "garment/sketch_inputs.hpp"

#include <fmt/format.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <vector>

#include "garment/body_up_error.hpp"
#include "garment/input_checks.hpp"
#include "garment/sketch_ranges.hpp"

namespace sd::garment {

Body load_sketch_body(const GarmentRequest& sketch) {
  return load_sketch_body(sketch, sketch.body, "/body");
}

Body load_sketch_body(const GarmentRequest& sketch, const BodySpec& spec,
                      const std::string& where) {
  if (spec.mesh == "none")
    sketch.fail(where + "/mesh",
                "a garment is designed on a body: give \"builtin\" or a body mesh "
                "file instead of \"none\"");
  BodyOptions options;
  options.height = spec.height;
  options.scale = spec.scale;
  // A sketched garment's body is a figure (a sheet's floor or rod is not: it has no curves).
  options.figure = !sketch.curves.empty();
  const std::string path = spec.mesh == "builtin" ? "builtin" : sketch.resolve(spec.mesh).string();
  try {
    if (spec.up) options.up = AxisDirection::parse(*spec.up);
    if (spec.facing) options.facing = AxisDirection::parse(*spec.facing);
    return load_body(path, options);
  } catch (const BodyUpError& e) {
    sketch.fail(where + "/up", e.what());
  } catch (const BodyFacingError& e) {
    sketch.fail(where + "/facing", e.what());
  } catch (const BodyError& e) {
    sketch.fail(where + "/mesh",
                fmt::format("the body '{}' cannot be used: {}", spec.mesh, e.what()));
  }
}

meshing::TriMesh load_garment_mesh(const GarmentRequest& sketch, long* file_faces) {
  const std::string where = "/garment_mesh";
  const std::filesystem::path path = sketch.resolve(*sketch.garment_mesh);
  if (const auto problem = input_file_problem(path, kMaxMeshFileBytes))
    sketch.fail(where, fmt::format("the garment mesh '{}' {}", path.string(), *problem));
  std::ifstream in(path);
  if (!in)
    sketch.fail(where,
                fmt::format("the garment mesh '{}' {}", path.string(),
                            std::filesystem::exists(path) ? "cannot be read" : "does not exist"));
  if (path.extension() != ".obj")
    sketch.fail(where, "a garment mesh must be a Wavefront .obj file");
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector3i> faces;
  long polygons = 0;
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    std::istringstream ls(line);
    std::string tag;
    ls >> tag;
    if (tag == "v") {
      Eigen::Vector3d p;
      if (!(ls >> p.x() >> p.y() >> p.z()) || !p.allFinite())
        sketch.fail(where, fmt::format("line {} of '{}' is not a vertex of three finite numbers",
                                       line_number, path.filename().string()));
      if (p.cwiseAbs().maxCoeff() > kMaxCoordinate)
        sketch.fail(
            where,
            fmt::format("line {} of '{}': a vertex {}", line_number, path.filename().string(),
                        out_of_range_sentence(p.cwiseAbs().maxCoeff(), -kMaxCoordinate,
                                              kMaxCoordinate, "at")));
      vertices.push_back(p);
    } else if (tag == "f") {
      std::vector<int> ids;
      std::string token;
      while (ls >> token) {
        const int index = std::atoi(token.substr(0, token.find('/')).c_str());
        const int resolved = index < 0 ? static_cast<int>(vertices.size()) + index : index - 1;
        if (index == 0 || resolved < 0 || resolved >= static_cast<int>(vertices.size()))
          sketch.fail(where, fmt::format("line {} of '{}' uses vertex {}, which does not exist",
                                         line_number, path.filename().string(), token));
        ids.push_back(resolved);
      }
      if (ids.size() < 3)
        sketch.fail(where, fmt::format("line {} of '{}' is a face with fewer than 3 vertices",
                                       line_number, path.filename().string()));
      for (size_t k = 1; k + 1 < ids.size(); ++k) faces.emplace_back(ids[0], ids[k], ids[k + 1]);
      ++polygons;
    }
  }
  if (faces.empty()) sketch.fail(where, fmt::format("'{}' has no faces", path.filename().string()));
  meshing::TriMesh mesh;
  mesh.vertices.resize(static_cast<Eigen::Index>(vertices.size()), 3);
  for (size_t v = 0; v < vertices.size(); ++v)
    mesh.vertices.row(static_cast<Eigen::Index>(v)) = vertices[v].transpose();
  mesh.faces.resize(static_cast<Eigen::Index>(faces.size()), 3);
  for (size_t f = 0; f < faces.size(); ++f)
    mesh.faces.row(static_cast<Eigen::Index>(f)) = faces[f].transpose();
  if (const auto problem = mesh_problem(mesh))
    sketch.fail(where, fmt::format("the garment mesh '{}' {}", path.filename().string(), *problem));
  if (file_faces != nullptr) *file_faces = polygons;
  return mesh;
}

}  // namespace sd::garment
