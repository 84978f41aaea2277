# penumbra_embed_files(<target> <symbol> <base_dir> FILES <f>...)
# Compiles the named files (relative to <base_dir>, or absolute: named by their file name) into <target> as a table {relative name, contents}, rebuilt when a
# file changes. The table is reachable through `penumbra::embedded::<symbol>()`.
function(penumbra_embed_files target symbol base_dir)
  cmake_parse_arguments(ARG "" "" "FILES" ${ARGN})
  set(out ${CMAKE_CURRENT_BINARY_DIR}/embedded_${symbol}.cpp)
  set(abs_files)
  foreach(f IN LISTS ARG_FILES)
    if(IS_ABSOLUTE ${f})
      list(APPEND abs_files ${f})
    else()
      list(APPEND abs_files ${base_dir}/${f})
    endif()
  endforeach()
  add_custom_command(
    OUTPUT ${out}
    COMMAND ${CMAKE_COMMAND} -DOUT=${out} -DSYMBOL=${symbol} -DBASE=${base_dir} "-DFILES=${ARG_FILES}"
            -P ${PROJECT_SOURCE_DIR}/cmake/EmbedFilesScript.cmake
    DEPENDS ${abs_files} ${PROJECT_SOURCE_DIR}/cmake/EmbedFilesScript.cmake
    COMMENT "Embedding ${symbol} (${CMAKE_CURRENT_LIST_DIR})"
    VERBATIM)
  target_sources(${target} PRIVATE ${out})
endfunction()
