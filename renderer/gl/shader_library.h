#pragma once
// Builds GL programs from the GLSL files embedded at build time (renderer/shaders/).
// `#include "file.glsl"` is expanded with `#line` markers so that compile and link errors name
// the original file and line, e.g. "pcf.glsl:42: error: ...".
#include <string>
#include <string_view>
#include <vector>

#include <penumbra/gl/objects.h>

namespace penumbra::gl {

struct ShaderDefine {
  std::string name;
  std::string value;
};

struct ShaderStage {
  GLenum type;       // GL_VERTEX_SHADER, GL_FRAGMENT_SHADER, GL_COMPUTE_SHADER
  std::string file;  // embedded file name
};

class ShaderLibrary {
 public:
  // Uses the embedded shaders table.
  ShaderLibrary();
  // For tests: an explicit set of {name, text} files.
  explicit ShaderLibrary(std::vector<std::pair<std::string, std::string>> files);

  // Compiles and links; throws std::runtime_error with file:line messages on failure.
  Program program(const std::vector<ShaderStage>& stages, const std::vector<ShaderDefine>& defines = {}) const;

  // The expanded source of `file` (after includes) and the file name of each `#line` source id.
  struct Expanded {
    std::string text;
    std::vector<std::string> source_names;
  };
  Expanded expand(const std::string& file, const std::vector<ShaderDefine>& defines) const;

  // Rewrites driver messages ("0:12(3): error" from Mesa, "0(12) : error" from NVIDIA) so that the
  // source number becomes the file name.
  static std::string map_log(std::string_view log, const std::vector<std::string>& source_names);

 private:
  const std::string& text_of(const std::string& file) const;
  std::vector<std::pair<std::string, std::string>> files_;
};

}  // namespace penumbra::gl
