#include "garment/input_checks.hpp"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <system_error>

namespace sd::garment {

std::optional<std::string> input_file_problem(const std::filesystem::path& path,
                                              std::uintmax_t max_bytes) {
  namespace fs = std::filesystem;
  std::error_code error;
  const fs::file_status link = fs::symlink_status(path, error);
  if (error && error != std::errc::no_such_file_or_directory)
    return fmt::format("cannot be examined ({})", error.message());
  if (!fs::exists(link)) return std::string("does not exist");
  const fs::file_status status = fs::status(path, error);
  if (error) {
    if (error == std::errc::too_many_symbolic_link_levels)
      return std::string("is a symbolic link that loops (it points back to itself)");
    if (error == std::errc::no_such_file_or_directory)
      return std::string("is a symbolic link to a file that does not exist");
    return fmt::format("cannot be examined ({})", error.message());
  }
  switch (status.type()) {
    case fs::file_type::regular:
      break;
    case fs::file_type::directory:
      return std::string("is a folder, not a file");
    case fs::file_type::fifo:
      return std::string("is a named pipe (FIFO), not a file: give a file saved on disk");
    case fs::file_type::character:
    case fs::file_type::block:
      return std::string("is a device, not a file");
    case fs::file_type::socket:
      return std::string("is a socket, not a file");
    default:
      return std::string("is not a regular file");
  }
  const std::uintmax_t size = fs::file_size(path, error);
  if (error) return fmt::format("cannot be examined ({})", error.message());
  if (size > max_bytes)
    return fmt::format("is {:.0f} MB, larger than the {:.0f} MB this program reads",
                       static_cast<double>(size) / 1e6, static_cast<double>(max_bytes) / 1e6);
  return std::nullopt;
}

std::optional<std::string> mesh_problem(const meshing::TriMesh& mesh) {
  if (mesh.face_count() == 0) return std::string("holds no triangles");
  if (mesh.faces.minCoeff() < 0 || mesh.faces.maxCoeff() >= mesh.vertex_count())
    return std::string("has a face that uses a vertex which does not exist");
  if (!mesh.vertices.allFinite()) return std::string("has NaN or infinite vertex coordinates");
  const Eigen::Vector3d extent =
      mesh.vertices.colwise().maxCoeff() - mesh.vertices.colwise().minCoeff();
  const double diagonal = extent.norm();
  if (!(diagonal > 0)) return std::string("has all its vertices at one point");
  const double min_area = 1e-12 * diagonal * diagonal;
  for (Eigen::Index f = 0; f < mesh.face_count(); ++f) {
    const Eigen::Vector3d a = mesh.vertices.row(mesh.faces(f, 0));
    const Eigen::Vector3d b = mesh.vertices.row(mesh.faces(f, 1));
    const Eigen::Vector3d c = mesh.vertices.row(mesh.faces(f, 2));
    if (0.5 * (b - a).cross(c - a).norm() > min_area) return std::nullopt;
  }
  return std::string("has no triangle with a non-zero area");
}

}  // namespace sd::garment
