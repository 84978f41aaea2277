# What `cmake --install` puts where (docs/install.md), and the Debian package (cpack -G DEB).
#
#   bin/                          the tools (component Runtime)
#   share/penumbra/               the data they ship with: calibration/, studies/, scenes/, and the
#                                 plot scripts in scripts/ (component Data); found by the tools
#                                 relative to their own directory (common/tool/tool.h)
#   share/doc/penumbra/           docs/, README.md and examples/ (component Documentation)
#   include/penumbra/             the public headers of the exported libraries  \
#   lib/libpenumbra_*.a           the exported static libraries                  } component Development
#   lib/cmake/Penumbra/           PenumbraConfig.cmake, its version file, the    |
#                                 exported targets per component                 |
#   lib/pkgconfig/                penumbra-adaptive.pc                           |
#   share/penumbra/shaders/       virtual_mark.comp, the virtual shadow map's    |
#                                 page marking, its includes inlined            /
#
# Exported targets (namespace Penumbra::), one export set, and so one file of targets, per component,
# each linking only what it needs; PenumbraConfig.cmake (cmake/PenumbraConfig.cmake.in) loads the
# components asked for and looks for their dependencies only:
#   adaptive       penumbra_adaptive: the rule, hysteresis, cascade sizing, calibration.json reader;
#                  no GL, GLM, study or Ceres, and nothing outside Penumbra
#   psychometrics  penumbra_psychometrics: models, QUEST, QUEST+, simulated observers
#   study_log      penumbra_study_log: the trial-log writer and validating reader
#   renderer       penumbra_renderer with gl, scene, io, image, sampling (epoxy, EGL, GLM,
#                  nlohmann_json, Assimp, and OpenImageIO or libpng + OpenEXR)
# and the internal set `core` the others link (published, random, text, json_input, staged_dir):
# installed as libraries, with headers only where a public header includes them.
#
# Headers are installed under include/penumbra and included as <penumbra/adaptive/resolution_rule.h>,
# by an engine and by each other; the targets put include/ alone on the include path (below).

include(CMakePackageConfigHelpers)

set(PENUMBRA_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/Penumbra)
set(PENUMBRA_INSTALL_INCLUDEDIR ${CMAKE_INSTALL_INCLUDEDIR}/penumbra)
set(PENUMBRA_BUILD_INCLUDEDIR ${PROJECT_BINARY_DIR}/include)  # its penumbra/: the public headers in the build

# --- stripped: `cmake --install` as `cmake --install --strip` --------------------------------------
#
# The tools' debug information made an installed prefix of ~320 MB (bin/ 257 MB, lib/ 63 MB) for
# ~26 MB of program (docs/install.md). Installed, they are stripped (CMake's own strip of each
# installed executable, and of the static archives below: --strip-debug, keeping their symbols),
# as `--strip` and the Debian package (CPACK_STRIP_FILES) always did. The first rule of the
# install script (the subdirectories have none) sets CMAKE_INSTALL_DO_STRIP, which the later
# rules read. A developer who wants an installed tool with its debug information configures with
# -DPENUMBRA_INSTALL_STRIP=OFF (`--strip` and the package still strip then).
option(PENUMBRA_INSTALL_STRIP "cmake --install strips the tools and libraries, with or without --strip" ON)
if(PENUMBRA_INSTALL_STRIP)
  install(CODE "set(CMAKE_INSTALL_DO_STRIP 1)  # PENUMBRA_INSTALL_STRIP (cmake/Install.cmake)" ALL_COMPONENTS)
endif()

# --- the tools, their data and the documentation ----------------------------------------------

set(penumbra_tools penumbra-render penumbra-scene penumbra-bench penumbra-demo penumbra-view
                   penumbra-quest penumbra-observer-curve penumbra-observer-fit penumbra-study penumbra-fit
                   penumbra-compare)
foreach(tool IN LISTS penumbra_tools)
  if(TARGET ${tool})
    install(TARGETS ${tool} RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT Runtime)
  endif()
endforeach()

install(DIRECTORY ${PROJECT_SOURCE_DIR}/data/ DESTINATION ${PENUMBRA_INSTALL_DATADIR} COMPONENT Data)
install(FILES ${PROJECT_SOURCE_DIR}/scripts/plot_bench.py ${PROJECT_SOURCE_DIR}/scripts/plot_demo.py
              ${PROJECT_SOURCE_DIR}/scripts/plot_fit.py
        DESTINATION ${PENUMBRA_INSTALL_DATADIR}/scripts COMPONENT Data)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/docs/ DESTINATION ${CMAKE_INSTALL_DOCDIR} COMPONENT Documentation)
install(FILES ${PROJECT_SOURCE_DIR}/README.md DESTINATION ${CMAKE_INSTALL_DOCDIR} COMPONENT Documentation)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/examples/ DESTINATION ${CMAKE_INSTALL_DOCDIR}/examples COMPONENT Documentation)

# --- the virtual shadow map's page marking for engines: share/penumbra/shaders/ ----------------------
#
# renderer/shaders/virtual_mark.comp with its includes (virtual_mark_contract.h, virtual_pages.glsl,
# shadow_contract.h, read_count.glsl) inlined, so that an engine compiles it as it is with its own #version and
# defines (GLSL has no #include; the renderer's gl::ShaderLibrary expands them, an engine's loader
# need not). Written at build time from the sources the renderer embeds, into build/install/shaders/
# (not build/share/penumbra: a tool in the build tree would take that for an installed tree), and
# installed with the Development component beside its C++ side,
# <penumbra/shaders/virtual_mark_contract.h> (below). docs/virtual-pages-in-your-engine.md;
# tests/install/test_virtual_mark_gl.cpp compiles the file below on the driver, alone.
set(PENUMBRA_VIRTUAL_MARK_GLSL ${PROJECT_BINARY_DIR}/install/shaders/virtual_mark.comp)
add_custom_command(
  OUTPUT ${PENUMBRA_VIRTUAL_MARK_GLSL}
  COMMAND ${CMAKE_COMMAND} -DDIR=${PROJECT_SOURCE_DIR}/renderer/shaders -DNAME=virtual_mark.comp -DOUT=${PENUMBRA_VIRTUAL_MARK_GLSL}
          -DVERSION=${PROJECT_VERSION} -P ${PROJECT_SOURCE_DIR}/cmake/FlattenGlsl.cmake
  DEPENDS ${PROJECT_SOURCE_DIR}/renderer/shaders/virtual_mark.comp ${PROJECT_SOURCE_DIR}/renderer/shaders/virtual_mark_contract.h
          ${PROJECT_SOURCE_DIR}/renderer/shaders/virtual_pages.glsl ${PROJECT_SOURCE_DIR}/renderer/shaders/shadow_contract.h
          ${PROJECT_SOURCE_DIR}/renderer/shaders/read_count.glsl
          ${PROJECT_SOURCE_DIR}/cmake/FlattenGlsl.cmake
  COMMENT "Inlining the includes of virtual_mark.comp for engines"
  VERBATIM)
add_custom_target(penumbra_virtual_mark_glsl ALL DEPENDS ${PENUMBRA_VIRTUAL_MARK_GLSL})
install(FILES ${PENUMBRA_VIRTUAL_MARK_GLSL} DESTINATION ${PENUMBRA_INSTALL_DATADIR}/shaders COMPONENT Development)

# --- libraries, headers, CMake package, pkg-config -----------------------------------------------

# component -> targets (export name = the target's name without "penumbra_")
set(penumbra_export_core penumbra_published penumbra_random penumbra_stats penumbra_psychometric_math penumbra_text
    penumbra_json_input penumbra_staged_dir)
set(penumbra_export_adaptive penumbra_adaptive)
set(penumbra_export_psychometrics penumbra_psychometrics)
set(penumbra_export_study_log penumbra_study_log)
set(penumbra_export_renderer penumbra_image penumbra_sampling penumbra_gl penumbra_scene penumbra_io penumbra_renderer)
set(penumbra_components adaptive psychometrics study_log renderer)
set(penumbra_export_file_core Core)  # Penumbra<...>Targets.cmake
set(penumbra_export_file_adaptive Adaptive)
set(penumbra_export_file_psychometrics Psychometrics)
set(penumbra_export_file_study_log StudyLog)
set(penumbra_export_file_renderer Renderer)

# The GL-free libraries are position independent, so that an engine can link them into a shared
# library (a plugin) too.
set_target_properties(${penumbra_export_core} ${penumbra_export_adaptive} ${penumbra_export_psychometrics}
                      ${penumbra_export_study_log} PROPERTIES POSITION_INDEPENDENT_CODE ON)
foreach(set IN ITEMS core ${penumbra_components})
  foreach(target IN LISTS penumbra_export_${set})
    string(REGEX REPLACE "^penumbra_" "" export_name ${target})
    set_target_properties(${target} PROPERTIES EXPORT_NAME ${export_name})
    # The standard the installed headers need: C++17 for the rule and the trial log, C++20 for
    # the psychometrics (std::numbers) and the renderer (concepts, std::span); the build itself
    # uses C++20 throughout.
    if(set STREQUAL "renderer" OR set STREQUAL "psychometrics")
      set(standard cxx_std_20)
    else()
      set(standard cxx_std_17)
    endif()
    get_target_property(type ${target} TYPE)
    if(type STREQUAL "INTERFACE_LIBRARY")
      set(scope INTERFACE)
    else()
      set(scope PUBLIC)
    endif()
    target_compile_features(${target} ${scope} ${standard})
    # <penumbra/...> in the build: the public headers' tree below (installed: include/).
    target_include_directories(${target} ${scope} $<BUILD_INTERFACE:${PENUMBRA_BUILD_INCLUDEDIR}>)
  endforeach()
  set(file_stem ${penumbra_export_file_${set}})
  install(TARGETS ${penumbra_export_${set}} EXPORT Penumbra${file_stem}
          ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT Development
          INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
  install(EXPORT Penumbra${file_stem} NAMESPACE Penumbra:: FILE Penumbra${file_stem}Targets.cmake
          DESTINATION ${PENUMBRA_INSTALL_CMAKEDIR} COMPONENT Development)
endforeach()

# --- public headers: include/penumbra/ when installed, build/include/penumbra/ in the build ----------
#
# A public header is included as <penumbra/adaptive/resolution_rule.h>, by an engine and by its
# installed siblings alike; only include/ goes on the consumer's include path. The sources keep their
# short includes ("adaptive/calibration.h", through the directories their targets already put on
# the build's include path). penumbra_public_headers() installs each header under
# include/penumbra/<subdir>/ and links it (a symbolic link to the source) into
# build/include/penumbra/<subdir>/, which every exported target puts on the build's include path:
# one list gives the installed tree and the build's, so what a public header includes resolves
# alike in both, and only headers on this list can be reached as <penumbra/...>.
# tests/install/consumer_test.sh checks the installed headers with include/ alone.
set(penumbra_public_header_links "")
function(penumbra_public_headers subdir)
  install(FILES ${ARGN} DESTINATION ${PENUMBRA_INSTALL_INCLUDEDIR}/${subdir} COMPONENT Development)
  set(links ${penumbra_public_header_links})
  foreach(header IN LISTS ARGN)
    cmake_path(GET header FILENAME name)
    cmake_path(APPEND PENUMBRA_BUILD_INCLUDEDIR penumbra ${subdir} ${name} OUTPUT_VARIABLE link)
    if(link IN_LIST links)
      message(FATAL_ERROR "penumbra: two public headers at ${link}")
    endif()
    list(APPEND links ${link})
    if(IS_SYMLINK ${link})
      file(READ_SYMLINK ${link} target)
    else()
      set(target "")
    endif()
    if(NOT target STREQUAL header)  # made once; a configure leaves it (and what depends on it) alone
      cmake_path(GET link PARENT_PATH dir)
      file(MAKE_DIRECTORY ${dir})
      file(CREATE_LINK ${header} ${link} SYMBOLIC)
    endif()
  endforeach()
  set(penumbra_public_header_links ${links} PARENT_SCOPE)
endfunction()
penumbra_public_headers("" ${PROJECT_SOURCE_DIR}/common/published.h)
penumbra_public_headers(sampling ${PROJECT_SOURCE_DIR}/common/sampling/random.h)
penumbra_public_headers(psychometric ${PROJECT_SOURCE_DIR}/common/psychometric/psychometric.h)
file(GLOB headers CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/renderer/adaptive/*.h)
penumbra_public_headers(adaptive ${headers})
file(GLOB headers CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/study/quest/*.h)
penumbra_public_headers(quest ${headers})
# observers/image_observer.h belongs to penumbra_study (GL), which is not installed.
penumbra_public_headers(observers ${PROJECT_SOURCE_DIR}/study/observers/observer.h
                        ${PROJECT_SOURCE_DIR}/study/observers/psychometric_observer.h
                        ${PROJECT_SOURCE_DIR}/study/observers/staircase_simulation.h)
file(GLOB headers CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/study/log/*.h)
penumbra_public_headers(log ${headers})
# The renderer: everything its headers reach (gl/window.h is the GUI's, io/image_codec.h the
# image backend's, neither installed).
penumbra_public_headers(image ${PROJECT_SOURCE_DIR}/common/image/image.h)
penumbra_public_headers(sampling ${PROJECT_SOURCE_DIR}/common/sampling/poisson_disk.h)
foreach(h context embedded_files objects shader_library timer)
  penumbra_public_headers(gl ${PROJECT_SOURCE_DIR}/renderer/gl/${h}.h)
endforeach()
penumbra_public_headers(io ${PROJECT_SOURCE_DIR}/renderer/io/image_io.h ${PROJECT_SOURCE_DIR}/renderer/io/report.h)
penumbra_public_headers(shaders ${PROJECT_SOURCE_DIR}/renderer/shaders/shadow_contract.h
                        ${PROJECT_SOURCE_DIR}/renderer/shaders/virtual_mark_contract.h)
foreach(dir scene shadows shadows/techniques)
  file(GLOB headers CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/renderer/${dir}/*.h)
  penumbra_public_headers(${dir} ${headers})
endforeach()
# A header no longer public (or renamed) leaves no link behind.
file(GLOB_RECURSE links LIST_DIRECTORIES false ${PENUMBRA_BUILD_INCLUDEDIR}/*)
foreach(link IN LISTS links)
  if(NOT link IN_LIST penumbra_public_header_links)
    file(REMOVE ${link})
  endif()
endforeach()

# Static archives: CMake strips installed executables only; these lose their debug information
# (not their symbols) when installing strips (above).
install(CODE "
  if(CMAKE_INSTALL_DO_STRIP)
    file(GLOB archives \"\$ENV{DESTDIR}\${CMAKE_INSTALL_PREFIX}/${CMAKE_INSTALL_LIBDIR}/libpenumbra_*.a\")
    foreach(a IN LISTS archives)
      execute_process(COMMAND \"${CMAKE_STRIP}\" --strip-debug \"\${a}\" COMMAND_ERROR_IS_FATAL ANY)
    endforeach()
  endif()" COMPONENT Development)

if(PENUMBRA_IMAGE_IO STREQUAL "OpenImageIO")
  set(PENUMBRA_IMAGE_IO_PACKAGES OpenImageIO)
  set(PENUMBRA_IMAGE_IO_TEXT OpenImageIO)
else()
  set(PENUMBRA_IMAGE_IO_PACKAGES PNG OpenEXR)
  set(PENUMBRA_IMAGE_IO_TEXT "PNG and OpenEXR")
endif()
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/PenumbraConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/install/PenumbraConfig.cmake
                              INSTALL_DESTINATION ${PENUMBRA_INSTALL_CMAKEDIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/install/PenumbraConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)  # 0.x: a new minor version may break
install(FILES ${PROJECT_BINARY_DIR}/install/PenumbraConfig.cmake ${PROJECT_BINARY_DIR}/install/PenumbraConfigVersion.cmake
        DESTINATION ${PENUMBRA_INSTALL_CMAKEDIR} COMPONENT Development)

# penumbra-adaptive.pc: everything is filled in now but the prefix, which is the one of the
# install (`cmake --install --prefix`, /usr in the Debian package), written when installing into a
# directory of its own (two installs may run at once).
set(PENUMBRA_PC_PREFIX "@PENUMBRA_PC_PREFIX@")
configure_file(${PROJECT_SOURCE_DIR}/cmake/penumbra-adaptive.pc.in ${PROJECT_BINARY_DIR}/install/penumbra-adaptive.pc.in @ONLY)
install(CODE "
  set(PENUMBRA_PC_PREFIX \"\${CMAKE_INSTALL_PREFIX}\")
  string(MD5 pc_dir \"\$ENV{DESTDIR}\${CMAKE_INSTALL_PREFIX}\")
  set(pc_dir \"${PROJECT_BINARY_DIR}/install/pc-\${pc_dir}\")
  configure_file(\"${PROJECT_BINARY_DIR}/install/penumbra-adaptive.pc.in\" \"\${pc_dir}/penumbra-adaptive.pc\" @ONLY)
  file(INSTALL \"\${pc_dir}/penumbra-adaptive.pc\" DESTINATION \"\${CMAKE_INSTALL_PREFIX}/${CMAKE_INSTALL_LIBDIR}/pkgconfig\")
  file(REMOVE_RECURSE \"\${pc_dir}\")" COMPONENT Development)

# --- the Debian package: cpack -G DEB (tests/install/deb_test.sh) ------------------------------

set(CPACK_PACKAGE_NAME penumbra)
set(CPACK_PACKAGE_VENDOR "Penumbra")
set(CPACK_PACKAGE_CONTACT "Penumbra maintainers <penumbra@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "perceptually chosen shadow-map resolution: renderer, study, fitter, library")
set(CPACK_PACKAGE_DESCRIPTION "An OpenGL 4.5 shadow-mapping renderer, a 2AFC study with QUEST staircases, a Ceres fitter for\n\
the constant c of the resolution rule r = c a, and the rule itself as a library (CMake package\n\
Penumbra, pkg-config penumbra-adaptive).")
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_STRIP_FILES ON)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION graphics)
# dpkg-shlibdeps names the shared libraries the tools link (dpkg-dev, scripts/setup.sh); libEGL is
# not linked but opened by libepoxy at run time, and no GL context is made without it.
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_DEPENDS "libegl1")
# Loaded at run time, not linked: a GL driver for EGL (Mesa's, or a GPU vendor's) and Python for the plots.
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "libegl-mesa0, libgl1-mesa-dri, python3-matplotlib")
# What the installed CMake package's renderer component needs to build against (the GL-free
# components need nothing).
if(PENUMBRA_IMAGE_IO STREQUAL "OpenImageIO")
  set(penumbra_image_dev libopenimageio-dev)
else()
  set(penumbra_image_dev "libpng-dev, libopenexr-dev")
endif()
set(CPACK_DEBIAN_PACKAGE_SUGGESTS "libepoxy-dev, libegl-dev, libglm-dev, nlohmann-json3-dev, libassimp-dev, ${penumbra_image_dev}, pkg-config")
set(CPACK_GENERATOR DEB)
include(CPack)
