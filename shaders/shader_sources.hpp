#pragma once
// The GLSL sources of shaders/*.glsl, embedded into the binary at build time so that the
// installed sketchdrape runs from any directory.

#include <optional>
#include <string_view>
#include <vector>

namespace sd::shaders {

// Source text of a shader file by its file name ("body.vert"), or nullopt if there is none.
std::optional<std::string_view> source(std::string_view name);

// File names of every embedded shader.
std::vector<std::string_view> names();

}  // namespace sd::shaders
