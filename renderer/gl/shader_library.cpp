#include "gl/shader_library.h"

#include <algorithm>
#include <cstring>
#include <functional>
#include <regex>
#include <sstream>
#include <stdexcept>

#include "gl/embedded_files.h"

namespace penumbra::gl {

ShaderLibrary::ShaderLibrary() {
  for (const auto& f : embedded::shaders()) files_.emplace_back(std::string(f.name), std::string(f.text));
}

ShaderLibrary::ShaderLibrary(std::vector<std::pair<std::string, std::string>> files) : files_(std::move(files)) {}

const std::string& ShaderLibrary::text_of(const std::string& file) const {
  for (const auto& [name, text] : files_)
    if (name == file) return text;
  throw std::runtime_error("shader file '" + file + "' is not embedded (is it listed in renderer/CMakeLists.txt?)");
}

namespace {

// Each file's lines are numbered from id * kLinesPerFile, so an error's line number alone tells its
// file: some drivers (Mesa 22) report errors in included files under the wrong source id.
constexpr long kLinesPerFile = 100000;

std::string line_marker(int line, int id) {
  return "#line " + std::to_string(id * kLinesPerFile + line) + " " + std::to_string(id) + "\n";
}

void expand_into(const std::string& file, const std::string& text,
                 std::vector<std::string>& names, std::vector<std::string>& stack, std::string& out,
                 const std::function<const std::string&(const std::string&)>& lookup) {
  if (std::find(stack.begin(), stack.end(), file) != stack.end())
    throw std::runtime_error("shader include cycle through '" + file + "'");
  stack.push_back(file);
  const int id = static_cast<int>(names.size());
  names.push_back(file);
  out += line_marker(1, id);
  static const std::regex include_re(R"(^\s*#\s*include\s+"([^"]+)\"\s*$)");
  std::istringstream in(text);
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    std::smatch m;
    if (std::regex_match(line, m, include_re)) {
      const std::string inc = m[1];
      expand_into(inc, lookup(inc), names, stack, out, lookup);
      out += line_marker(line_no + 1, id);
    } else {
      out += line;
      out += '\n';
    }
  }
  stack.pop_back();
}

// The info log of a shader or program, through its pair of query functions.
template <class GetIv, class GetLog>
std::string info_log(GLuint object, GetIv get_iv, GetLog get_log) {
  GLint len = 0;
  get_iv(object, GL_INFO_LOG_LENGTH, &len);
  std::string log(static_cast<std::size_t>(std::max(len, 1)), '\0');
  get_log(object, len, nullptr, log.data());
  log.resize(std::strlen(log.c_str()));
  return log;
}

std::string stage_name(GLenum type) {
  switch (type) {
    case GL_VERTEX_SHADER: return "vertex";
    case GL_FRAGMENT_SHADER: return "fragment";
    case GL_COMPUTE_SHADER: return "compute";
    default: return "shader";
  }
}

}  // namespace

ShaderLibrary::Expanded ShaderLibrary::expand(const std::string& file, const std::vector<ShaderDefine>& defines) const {
  Expanded e;
  e.text = "#version 450 core\n";
  for (const auto& d : defines) e.text += "#define " + d.name + " " + d.value + "\n";
  std::vector<std::string> stack;
  expand_into(file, text_of(file), e.source_names, stack, e.text,
              [this](const std::string& f) -> const std::string& { return text_of(f); });
  return e;
}

std::string ShaderLibrary::map_log(std::string_view log, const std::vector<std::string>& source_names) {
  static const std::regex mesa_re(R"((^|\n)(\d+):(\d+)\((\d+)\):)");
  static const std::regex nvidia_re(R"((^|\n)(\d+)\((\d+)\) :)");
  auto name_of = [&](const std::string& id) {
    const auto i = static_cast<std::size_t>(std::stoul(id));
    return i < source_names.size() ? source_names[i] : "source" + id;
  };
  // File and line from an encoded line number (see kLinesPerFile); the reported id otherwise.
  auto locate = [&](const std::string& id, const std::string& line) {
    const long n = std::stol(line);
    if (n < kLinesPerFile) return name_of(id) + ":" + line;
    return name_of(std::to_string(n / kLinesPerFile)) + ":" + std::to_string(n % kLinesPerFile);
  };
  std::string text(log);
  std::string out;
  std::smatch m;
  auto rewrite = [&](const std::regex& re, bool mesa) {
    out.clear();
    auto begin = text.cbegin();
    while (std::regex_search(begin, text.cend(), m, re)) {
      out.append(begin, m[0].first);
      out += m[1].str() + locate(m[2].str(), m[3].str()) + ":";
      if (mesa) out += m[4].str() + ":";
      begin = m[0].second;
    }
    out.append(begin, text.cend());
    text = out;
  };
  rewrite(mesa_re, true);
  rewrite(nvidia_re, false);
  return text;
}

Program ShaderLibrary::program(const std::vector<ShaderStage>& stages, const std::vector<ShaderDefine>& defines) const {
  std::vector<GLuint> shaders;
  auto cleanup = [&] {
    for (GLuint s : shaders) glDeleteShader(s);
  };
  GLuint prog = glCreateProgram();
  std::string names;
  try {
    for (const auto& stage : stages) {
      const Expanded e = expand(stage.file, defines);
      GLuint s = glCreateShader(stage.type);
      shaders.push_back(s);
      const char* src = e.text.c_str();
      glShaderSource(s, 1, &src, nullptr);
      glCompileShader(s);
      GLint ok = 0;
      glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
      if (!ok) {
        throw std::runtime_error("GLSL compile error in " + stage.file + " (" + stage_name(stage.type) +
                                 " stage):\n" + map_log(info_log(s, glGetShaderiv, glGetShaderInfoLog), e.source_names));
      }
      glAttachShader(prog, s);
      names += (names.empty() ? "" : " + ") + stage.file;
    }
    glLinkProgram(prog);
    GLint ok = 0;
    glGetProgramiv(prog, GL_LINK_STATUS, &ok);
    if (!ok) throw std::runtime_error("GLSL link error in " + names + ":\n" + info_log(prog, glGetProgramiv, glGetProgramInfoLog));
  } catch (...) {
    cleanup();
    glDeleteProgram(prog);
    throw;
  }
  cleanup();
  glObjectLabel(GL_PROGRAM, prog, -1, names.c_str());
  return Program(prog);
}

}  // namespace penumbra::gl
