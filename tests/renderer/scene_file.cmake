# Scene files (renderer/scene/scene_file.cpp): examples in data/scenes, models, error messages.
add_executable(test_scene_file ${CMAKE_CURRENT_LIST_DIR}/test_scene_file.cpp)
target_link_libraries(test_scene_file PRIVATE penumbra_scene GTest::gtest_main penumbra_warnings)
target_compile_definitions(test_scene_file PRIVATE PENUMBRA_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
gtest_discover_tests(test_scene_file PROPERTIES LABELS unit)

# The procedural outdoor scene: determinism, size, build and load time, scene-file round trip.
add_executable(test_outdoor_scene ${CMAKE_CURRENT_LIST_DIR}/test_outdoor_scene.cpp)
target_link_libraries(test_outdoor_scene PRIVATE penumbra_scene GTest::gtest_main penumbra_warnings)
gtest_discover_tests(test_outdoor_scene PROPERTIES LABELS unit)
