# Settings tables, the shader library, and penumbra-render run as a subprocess.
add_executable(test_settings ${CMAKE_CURRENT_LIST_DIR}/test_settings.cpp)
target_link_libraries(test_settings PRIVATE penumbra_renderer GTest::gmock GTest::gtest_main penumbra_warnings)
gtest_discover_tests(test_settings PROPERTIES LABELS unit)

# One binary, two labels: the ShaderLibraryGl suite needs an OpenGL context, the rest does not.
add_executable(test_shader_library ${CMAKE_CURRENT_LIST_DIR}/test_shader_library.cpp)
target_link_libraries(test_shader_library PRIVATE penumbra_renderer GTest::gmock GTest::gtest_main penumbra_warnings)
gtest_discover_tests(test_shader_library TEST_LIST test_shader_library_unit TEST_FILTER "-ShaderLibraryGl.*"
                     PROPERTIES LABELS unit)
gtest_discover_tests(test_shader_library TEST_LIST test_shader_library_gl TEST_FILTER "ShaderLibraryGl.*"
                     PROPERTIES LABELS gl DISCOVERY_TIMEOUT 60)

add_executable(test_render_cli ${CMAKE_CURRENT_LIST_DIR}/test_render_cli.cpp)
target_link_libraries(test_render_cli PRIVATE penumbra_renderer GTest::gmock GTest::gtest_main penumbra_warnings)
target_compile_definitions(test_render_cli PRIVATE PENUMBRA_RENDER_EXE="$<TARGET_FILE:penumbra-render>")
add_dependencies(test_render_cli penumbra-render)
gtest_discover_tests(test_render_cli PROPERTIES LABELS e2e TIMEOUT 300)

add_executable(test_scene_cli ${CMAKE_CURRENT_LIST_DIR}/test_scene_cli.cpp)
target_link_libraries(test_scene_cli PRIVATE penumbra_scene GTest::gmock GTest::gtest_main penumbra_warnings)
target_compile_definitions(test_scene_cli PRIVATE PENUMBRA_SCENE_EXE="$<TARGET_FILE:penumbra-scene>")
add_dependencies(test_scene_cli penumbra-scene)
gtest_discover_tests(test_scene_cli PROPERTIES LABELS e2e TIMEOUT 120)
