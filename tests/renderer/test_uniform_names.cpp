// Issue 28: uniforms are set by name (gl::Program::set) and a name the program lacks is ignored,
// as GL ignores location -1, which is what lets one technique's setter serve every variant of a
// program. The price was that a misspelt name failed silently. This test makes it fail loudly:
// every uniform name C++ sets as a literal must be declared by some shader of renderer/shaders.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <set>
#include <string>

namespace fs = std::filesystem;

namespace {

std::string read(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

TEST(UniformNames, EveryNameSetFromCppIsDeclaredInAShader) {
  const fs::path root = PENUMBRA_SOURCE_DIR;
  std::set<std::string> declared;
  const std::regex declaration(R"(uniform\s+(?:(?:highp|mediump|lowp|coherent|volatile|restrict|readonly|writeonly)\s+)*\w+\s+(u_\w+))");
  for (const auto& e : fs::directory_iterator(root / "renderer" / "shaders")) {
    const std::string text = read(e.path());
    for (std::sregex_iterator it(text.begin(), text.end(), declaration), end; it != end; ++it) declared.insert((*it)[1]);
  }
  ASSERT_GT(declared.size(), 20u) << "no uniform declarations found under renderer/shaders";
  // set("u_x", ...) and binding("u_x") (the unit a sampler or image was given in the shader;
  // binding() also throws at run time when the program lacks it).
  const std::regex set_call(R"(\b(?:set|binding)\(\s*"(u_\w+))");
  int calls = 0;
  for (const char* dir : {"renderer", "study"})
    for (const auto& e : fs::recursive_directory_iterator(root / dir)) {
      const std::string ext = e.path().extension().string();
      if (ext != ".cpp" && ext != ".h") continue;
      const std::string text = read(e.path());
      for (std::sregex_iterator it(text.begin(), text.end(), set_call), end; it != end; ++it) {
        ++calls;
        EXPECT_TRUE(declared.count((*it)[1])) << fs::relative(e.path(), root).string() << " sets " << (*it)[1]
                                              << ", which no shader of renderer/shaders declares";
      }
    }
  EXPECT_GT(calls, 30) << "no uniform set calls found: the pattern no longer matches the code";
}

}  // namespace
