#pragma once
// Checks shared by every command that reads a user's file: the path must be a regular file (a
// FIFO would block the reader for ever, a device or a folder is not a mesh, a symbolic link loop
// throws from std::filesystem), and a mesh must have some area. Each returns the sentence that
// ends "'<file>' ..." when the input is unusable, nothing when it is fine.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

#include "meshing/tri_mesh.hpp"

namespace sd::garment {

// Why `path` cannot be read as an input file ("does not exist", "is a named pipe (FIFO) ...",
// "is larger than ..."), or nothing. Never blocks and never throws.
std::optional<std::string> input_file_problem(const std::filesystem::path& path,
                                              std::uintmax_t max_bytes);

// Why `mesh` cannot be used as a surface (a face index out of range, non-finite coordinates, all
// vertices at one point, no triangle with a non-zero area), or nothing.
std::optional<std::string> mesh_problem(const meshing::TriMesh& mesh);

}  // namespace sd::garment
