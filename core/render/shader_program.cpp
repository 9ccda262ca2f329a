#include "core/render/shader_program.h"

#include <algorithm>
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

GLuint compile(GLenum type, std::string_view file, std::string_view defines) {
  const std::string path = shaderPath(file).string();
  std::string source = readFile(path);
  if (!defines.empty()) {
    const size_t version = source.find("#version");
    const size_t line_end = version == std::string::npos ? 0 : source.find('\n', version) + 1;
    // #line keeps the driver's line numbers those of the file.
    const size_t line = size_t(std::count(source.begin(), source.begin() + line_end, '\n')) + 1;
    source.insert(line_end, std::string(defines) + "\n#line " + std::to_string(line) + "\n");
  }
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

ShaderProgram::ShaderProgram(std::string_view vertex_file, std::string_view fragment_file,
                             std::string_view defines) {
  const GLuint vertex = compile(GL_VERTEX_SHADER, vertex_file, defines);
  GLuint fragment = 0;
  try {
    fragment = compile(GL_FRAGMENT_SHADER, fragment_file, defines);
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
