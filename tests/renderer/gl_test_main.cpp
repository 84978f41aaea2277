// main() of the GL test binaries: one headless OpenGL context for the whole run.
#include <gtest/gtest.h>

#include "gl_test_env.h"

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ::testing::AddGlobalTestEnvironment(new penumbra::test::GlEnvironment);
  return RUN_ALL_TESTS();
}
