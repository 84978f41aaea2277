// penumbra-scene as a user runs it: it describes a scene, writes one that loads back, and refuses
// bad input with one line and nothing written.
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "scene/scene.h"
#include "subprocess.h"

namespace fs = std::filesystem;
using ::testing::HasSubstr;

namespace {

class SceneCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("penumbra-scene-test-" + std::to_string(::getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  penumbra::test::Result scene(const std::vector<std::string>& args) { return penumbra::test::run_exe(PENUMBRA_SCENE_EXE, args, dir_); }
  fs::path dir_;
};

TEST_F(SceneCli, DescribesAndWritesAScene) {
  const fs::path out = dir_ / "demo";
  const auto r = scene({"--scene", "demo", "-o", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("fence"));
  EXPECT_THAT(r.out, HasSubstr("total"));
  const penumbra::scene::Scene back = penumbra::scene::load_scene_file(out / "scene.json");
  const penumbra::scene::Scene original = penumbra::scene::make_builtin_scene("demo");
  ASSERT_EQ(back.objects.size(), original.objects.size());
  EXPECT_EQ(back.objects[3].name, "fence");
  EXPECT_EQ(back.objects[3].mesh->indices.size(), original.objects[3].mesh->indices.size());
}

TEST_F(SceneCli, BadInputIsOneLineAndWritesNothing) {
  const fs::path out = dir_ / "out";
  struct Case {
    std::vector<std::string> args;
    std::string says;
  };
  const Case cases[] = {
      {{"--scene", "demo", "--seed", "3"}, "--seed: only the outdoor scenes"},
      {{"--scene", "nowhere"}, "nowhere"},
      {{"--scene", "outdoor", "--seed", "-1"}, "--seed"},
  };
  for (const auto& c : cases) {
    std::vector<std::string> args = c.args;
    args.insert(args.end(), {"-o", out.string()});
    const auto r = scene(args);
    EXPECT_NE(r.exit_code, 0) << c.says;
    EXPECT_THAT(r.err, HasSubstr(c.says));
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_FALSE(fs::exists(out)) << c.says;
  }
}

}  // namespace
