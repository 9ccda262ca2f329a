#pragma once

#include <string>
#include <string_view>

#include "core/render/gl.h"

namespace lumistage {

// A linked GLSL program built from files in shaders/ (found like resources: see shaderPath).
// Throws Error with the file name and the driver's log on a compile or link error.
class ShaderProgram {
 public:
  // `defines` (e.g. "#define kOwnCameras 3\n") is inserted after each file's #version line.
  ShaderProgram(std::string_view vertex_file, std::string_view fragment_file,
                std::string_view defines = {});
  ~ShaderProgram();
  ShaderProgram(const ShaderProgram&) = delete;
  ShaderProgram& operator=(const ShaderProgram&) = delete;

  GLuint id() const { return program_; }
  void use() const { glUseProgram(program_); }
  GLint uniform(const char* name) const { return glGetUniformLocation(program_, name); }

 private:
  GLuint program_ = 0;
};

}  // namespace lumistage
