#pragma once
// A linked GLSL program built from the embedded shader files (internal to sd_render).

#include <Eigen/Core>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "src/render/gl.hpp"

namespace sd::render {

// Source of embedded shader `name` with every line `#include "other"` replaced by the text of
// that embedded file (one level deep). Throws RenderError if a file is missing.
std::string expand_shader_includes(std::string_view name);

class ShaderProgram {
 public:
  // Compiles and links the named stages, e.g. {{GL_VERTEX_SHADER, "mesh.vert"}, ...}. The
  // context must be current. Throws RenderError with the GLSL log.
  ShaderProgram(std::vector<std::pair<GLenum, std::string_view>> stages);
  ~ShaderProgram();
  ShaderProgram(const ShaderProgram&) = delete;
  ShaderProgram& operator=(const ShaderProgram&) = delete;

  void use() const { glUseProgram(id_); }
  void set(const char* name, int value);
  void set(const char* name, float value);
  void set(const char* name, const Eigen::Vector2f& value);
  void set(const char* name, const Eigen::Vector3f& value);
  void set(const char* name, const Eigen::Matrix4f& value);

 private:
  GLint location(const char* name);
  GLuint id_ = 0;
  std::string label_;
  std::unordered_map<std::string, GLint> locations_;
};

}  // namespace sd::render
