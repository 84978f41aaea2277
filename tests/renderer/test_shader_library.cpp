// The shader library (renderer/gl/shader_library.h): `#include` expansion with `#line` markers,
// driver logs mapped back to file:line, and (suite ShaderLibraryGl, label `gl`) real compiles:
// a broken included file is reported at its own file and line, and every program the renderer
// builds compiles on this driver.
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "gl/context.h"
#include "gl/shader_library.h"
#include "shadows/renderer.h"

using penumbra::gl::ShaderDefine;
using penumbra::gl::ShaderLibrary;
using penumbra::gl::ShaderStage;
using ::testing::HasSubstr;
using ::testing::Not;

namespace {

using Files = std::vector<std::pair<std::string, std::string>>;

std::string thrown_message(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected std::runtime_error";
  return {};
}

}  // namespace

TEST(ShaderLibrary, IncludesExpandWithLineMarkersAndSourceNames) {
  const ShaderLibrary lib(Files{
      {"main.frag", "void main() {}\n#include \"a.glsl\"\nmain3\n  #  include \"b.glsl\"  \nmain5\n"},
      {"a.glsl", "a1\n#include \"b.glsl\"\na3\n"},
      {"b.glsl", "b1\n// #include \"nope.glsl\" is a comment, not an include\n"},
  });
  const auto e = lib.expand("main.frag", {{"TECHNIQUE_PCF", "1"}, {"TAPS", "25"}});
  // `#line N id` sets the number of the *next* line, so after an include the including file
  // resumes at the line after the directive.
  EXPECT_EQ(e.text,
            "#version 450 core\n"
            "#define TECHNIQUE_PCF 1\n"
            "#define TAPS 25\n"
            "#line 1 0\n"
            "void main() {}\n"
            "#line 100001 1\n"
            "a1\n"
            "#line 200001 2\n"
            "b1\n"
            "// #include \"nope.glsl\" is a comment, not an include\n"
            "#line 100003 1\n"
            "a3\n"
            "#line 3 0\n"
            "main3\n"
            "#line 300001 3\n"
            "b1\n"
            "// #include \"nope.glsl\" is a comment, not an include\n"
            "#line 5 0\n"
            "main5\n");
  EXPECT_EQ(e.source_names, (std::vector<std::string>{"main.frag", "a.glsl", "b.glsl", "b.glsl"}));
}

TEST(ShaderLibrary, IncludeCyclesThrowNamingTheFile) {
  const ShaderLibrary lib(Files{
      {"main.frag", "#include \"a.glsl\"\n"},
      {"a.glsl", "#include \"b.glsl\"\n"},
      {"b.glsl", "#include \"a.glsl\"\n"},
      {"self.glsl", "x\n#include \"self.glsl\"\n"},
  });
  const std::string cycle = thrown_message([&] { lib.expand("main.frag", {}); });
  EXPECT_THAT(cycle, HasSubstr("cycle"));
  EXPECT_THAT(cycle, HasSubstr("a.glsl"));
  const std::string self = thrown_message([&] { lib.expand("self.glsl", {}); });
  EXPECT_THAT(self, HasSubstr("cycle"));
  EXPECT_THAT(self, HasSubstr("self.glsl"));
}

TEST(ShaderLibrary, UnknownFilesThrowNamingTheFile) {
  const ShaderLibrary lib(Files{{"main.frag", "x\n#include \"missing.glsl\"\n"}});
  EXPECT_THAT(thrown_message([&] { lib.expand("nope.frag", {}); }), HasSubstr("'nope.frag'"));
  EXPECT_THAT(thrown_message([&] { lib.expand("main.frag", {}); }), HasSubstr("'missing.glsl'"));
}

TEST(ShaderLibrary, EmbeddedLibraryHasTheRenderersFiles) {
  const ShaderLibrary lib;
  for (const char* f : {"shading.frag", "shading.vert", "shadow_depth.vert", "vsm_blur.comp"}) {
    SCOPED_TRACE(f);
    const auto e = lib.expand(f, {});
    EXPECT_EQ(e.text.rfind("#version 450 core\n", 0), 0u);
    ASSERT_FALSE(e.source_names.empty());
    EXPECT_EQ(e.source_names[0], f);
  }
}

TEST(ShaderLibrary, MapLogRewritesMesaMessages) {
  const std::vector<std::string> names = {"main.frag", "pcf.glsl"};
  EXPECT_EQ(ShaderLibrary::map_log("0:12(3): error: x", names), "main.frag:12:3: error: x");
  EXPECT_EQ(ShaderLibrary::map_log("1:42(17): error: `foo' undeclared\n0:7(1): warning: unused\n", names),
            "pcf.glsl:42:17: error: `foo' undeclared\nmain.frag:7:1: warning: unused\n");
  // A source id with no name is still readable rather than silently wrong.
  EXPECT_EQ(ShaderLibrary::map_log("5:2(1): error: z", names), "source5:2:1: error: z");
  // Encoded line numbers name their file whatever source id the driver reports.
  EXPECT_EQ(ShaderLibrary::map_log("0:100042(17): error: w", names), "pcf.glsl:42:17: error: w");
}

TEST(ShaderLibrary, MapLogRewritesNvidiaMessages) {
  const std::vector<std::string> names = {"main.frag", "pcf.glsl"};
  EXPECT_EQ(ShaderLibrary::map_log("1(7) : error C1008: y", names), "pcf.glsl:7: error C1008: y");
  EXPECT_EQ(ShaderLibrary::map_log("0(12) : error C0000: a\n1(3) : warning C7050: b", names),
            "main.frag:12: error C0000: a\npcf.glsl:3: warning C7050: b");
}

TEST(ShaderLibrary, MapLogLeavesOtherTextAlone) {
  const std::vector<std::string> names = {"main.frag"};
  const std::string text = "error: linking failed\nvalue 0:12(3) mid-line stays\n";
  EXPECT_EQ(ShaderLibrary::map_log(text, names), text);
  EXPECT_EQ(ShaderLibrary::map_log("", names), "");
}

// --- needs an OpenGL 4.5 context (label `gl`) ---

class ShaderLibraryGl : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { context_ = std::make_unique<penumbra::gl::HeadlessContext>(); }
  static void TearDownTestSuite() { context_.reset(); }
  static inline std::unique_ptr<penumbra::gl::HeadlessContext> context_;
};

TEST_F(ShaderLibraryGl, CompileErrorNamesTheIncludedFileAndLine) {
  const ShaderLibrary lib(Files{
      {"main.frag",
       "layout(location = 0) out vec4 o_color;\n"
       "#include \"broken.glsl\"\n"
       "void main() { o_color = f(); }\n"},
      {"broken.glsl",
       "vec4 f() {\n"
       "  float a = 1.0;\n"
       "  return vec4(a) + undefined_thing;\n"
       "}\n"},
  });
  const std::string msg = thrown_message([&] { lib.program({{GL_FRAGMENT_SHADER, "main.frag"}}); });
  EXPECT_THAT(msg, HasSubstr("broken.glsl:3:19")) << msg;
  EXPECT_THAT(msg, HasSubstr("main.frag")) << msg;  // the stage being compiled
  // Mesa 22.3 reports this error under source 0; the per-file line numbering must still name
  // the included file, never a line of the including one.
  EXPECT_THAT(msg, Not(HasSubstr("main.frag:3:"))) << msg;
}

TEST_F(ShaderLibraryGl, CompileErrorAfterAnIncludeNamesTheIncludingFileAndLine) {
  const ShaderLibrary lib(Files{
      {"main.frag",
       "layout(location = 0) out vec4 o_color;\n"
       "#include \"ok.glsl\"\n"
       "void main() { o_color = f() + also_undefined; }\n"},
      {"ok.glsl", "vec4 f() {\n  return vec4(1.0);\n}\n"},
  });
  const std::string msg = thrown_message([&] { lib.program({{GL_FRAGMENT_SHADER, "main.frag"}}); });
  EXPECT_THAT(msg, HasSubstr("main.frag:3")) << msg;
}

TEST_F(ShaderLibraryGl, ValidProgramLinks) {
  const ShaderLibrary lib(Files{
      {"main.comp", "layout(local_size_x = 1) in;\nlayout(std430, binding = 0) buffer B { float v[]; };\n"
                    "void main() { v[0] = VALUE; }\n"},
  });
  const auto program = lib.program({{GL_COMPUTE_SHADER, "main.comp"}}, {{"VALUE", "2.0"}});
  EXPECT_NE(program.id(), 0u);
}

TEST_F(ShaderLibraryGl, RendererProgramsCompile) {
  EXPECT_NO_THROW({ penumbra::shadows::Renderer renderer; });
}

// Every shading-program variant Renderer::shading_program can ask for: one TECHNIQUE_* define,
// optionally KERNEL_GRID (taken from the PCF kernel for non-PCSS techniques, so it can come with
// any technique).
TEST_F(ShaderLibraryGl, EveryShadingVariantCompiles) {
  const ShaderLibrary lib;
  for (const char* technique : {"TECHNIQUE_HARD", "TECHNIQUE_PCF", "TECHNIQUE_PCSS", "TECHNIQUE_VSM"}) {
    for (bool grid : {false, true}) {
      std::vector<ShaderDefine> defines = {{technique, "1"}};
      if (grid) defines.push_back({"KERNEL_GRID", "1"});
      SCOPED_TRACE(std::string(technique) + (grid ? " + KERNEL_GRID" : ""));
      EXPECT_NO_THROW(lib.program({{GL_VERTEX_SHADER, "shading.vert"}, {GL_FRAGMENT_SHADER, "shading.frag"}}, defines));
    }
  }
}
