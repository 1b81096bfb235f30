#include "src/render/shader_program.hpp"

#include <fmt/format.h>

#include <sstream>

#include "shaders/shader_sources.hpp"
#include "src/render/renderer.hpp"

namespace sd::render {
namespace {

std::string_view embedded(std::string_view name) {
  const auto text = shaders::source(name);
  if (!text) throw RenderError(fmt::format("shader '{}' is not embedded in the binary", name));
  return *text;
}

std::string info_log(GLuint object, bool is_program) {
  GLint length = 0;
  is_program ? glGetProgramiv(object, GL_INFO_LOG_LENGTH, &length)
             : glGetShaderiv(object, GL_INFO_LOG_LENGTH, &length);
  std::string log(static_cast<size_t>(std::max(length, 1)), '\0');
  is_program ? glGetProgramInfoLog(object, length, nullptr, log.data())
             : glGetShaderInfoLog(object, length, nullptr, log.data());
  return log.c_str();
}

}  // namespace

std::string expand_shader_includes(std::string_view name) {
  std::istringstream lines{std::string(embedded(name))};
  std::string out, line;
  int number = 0;
  while (std::getline(lines, line)) {
    ++number;
    const size_t open = line.find('"');
    const size_t close = line.rfind('"');
    if (line.rfind("#include", 0) == 0 && open != std::string::npos && close > open) {
      out += embedded(std::string_view(line).substr(open + 1, close - open - 1));
      // Keep compiler messages pointing at the including file's line numbers.
      out += fmt::format("\n#line {}\n", number + 1);
    } else {
      out += line;
      out += '\n';
    }
  }
  return out;
}

ShaderProgram::ShaderProgram(std::vector<std::pair<GLenum, std::string_view>> stages) {
  id_ = glCreateProgram();
  std::vector<GLuint> shaders;
  for (const auto& [stage, name] : stages) {
    label_ += (label_.empty() ? "" : "+") + std::string(name);
    const std::string source = expand_shader_includes(name);
    const GLuint shader = glCreateShader(stage);
    const char* text = source.c_str();
    glShaderSource(shader, 1, &text, nullptr);
    glCompileShader(shader);
    GLint ok = GL_FALSE;
    glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (ok != GL_TRUE) {
      const std::string log = info_log(shader, false);
      glDeleteShader(shader);
      for (GLuint s : shaders) glDeleteShader(s);
      glDeleteProgram(id_);
      throw RenderError(fmt::format("shader {} does not compile:\n{}", name, log));
    }
    glAttachShader(id_, shader);
    shaders.push_back(shader);
  }
  glLinkProgram(id_);
  for (GLuint s : shaders) glDeleteShader(s);  // stays alive while attached
  GLint ok = GL_FALSE;
  glGetProgramiv(id_, GL_LINK_STATUS, &ok);
  if (ok != GL_TRUE) {
    const std::string log = info_log(id_, true);
    glDeleteProgram(id_);
    throw RenderError(fmt::format("shaders {} do not link:\n{}", label_, log));
  }
}

ShaderProgram::~ShaderProgram() {
  if (id_ != 0) glDeleteProgram(id_);
}

GLint ShaderProgram::location(const char* name) {
  const auto it = locations_.find(name);
  if (it != locations_.end()) return it->second;
  // -1 for a uniform the compiler optimised away; glUniform* ignores it, which is what we want.
  const GLint loc = glGetUniformLocation(id_, name);
  locations_.emplace(name, loc);
  return loc;
}

void ShaderProgram::set(const char* name, int value) {
  glUniform1i(location(name), value);
}
void ShaderProgram::set(const char* name, float value) {
  glUniform1f(location(name), value);
}
void ShaderProgram::set(const char* name, const Eigen::Vector2f& value) {
  glUniform2fv(location(name), 1, value.data());
}
void ShaderProgram::set(const char* name, const Eigen::Vector3f& value) {
  glUniform3fv(location(name), 1, value.data());
}
void ShaderProgram::set(const char* name, const Eigen::Matrix4f& value) {
  glUniformMatrix4fv(location(name), 1, GL_FALSE, value.data());  // Eigen is column-major
}

}  // namespace sd::render
