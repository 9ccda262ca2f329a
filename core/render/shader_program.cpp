#include "core/render/shader_program.h"

#include <vector>

#include "core/base/atomic_file.h"
#include "core/base/error.h"
#include "core/base/resource_path.h"

namespace lumistage {

namespace {

// The driver's log of a shader or program (glGetShaderiv/InfoLog or their Program twins).
template <typename GetIv, typename GetLog>
std::string infoLog(GLuint object, GetIv get_iv, GetLog get_log) {
  GLint length = 0;
  get_iv(object, GL_INFO_LOG_LENGTH, &length);
  std::vector<char> log(std::max(length, 1));
  get_log(object, length, nullptr, log.data());
  return log.data();
}

GLuint compile(GLenum type, std::string_view file) {
  const std::string path = shaderPath(file).string();
  const std::string source = readFile(path);
  const GLuint shader = glCreateShader(type);
  const char* text = source.c_str();
  glShaderSource(shader, 1, &text, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    const std::string log = infoLog(shader, glGetShaderiv, glGetShaderInfoLog);
    glDeleteShader(shader);
    throw Error(path + ": shader does not compile:\n" + log);
  }
  return shader;
}

}  // namespace

ShaderProgram::ShaderProgram(std::string_view vertex_file, std::string_view fragment_file) {
  const GLuint vertex = compile(GL_VERTEX_SHADER, vertex_file);
  GLuint fragment = 0;
  try {
    fragment = compile(GL_FRAGMENT_SHADER, fragment_file);
  } catch (...) {
    glDeleteShader(vertex);
    throw;
  }
  program_ = glCreateProgram();
  glAttachShader(program_, vertex);
  glAttachShader(program_, fragment);
  glLinkProgram(program_);
  glDeleteShader(vertex);
  glDeleteShader(fragment);
  GLint ok = 0;
  glGetProgramiv(program_, GL_LINK_STATUS, &ok);
  if (!ok) {
    const std::string log = infoLog(program_, glGetProgramiv, glGetProgramInfoLog);
    glDeleteProgram(program_);
    throw Error(std::string(vertex_file) + " + " + std::string(fragment_file) +
                ": program does not link:\n" + log);
  }
}

ShaderProgram::~ShaderProgram() {
  if (program_) glDeleteProgram(program_);
}

}  // namespace lumistage
