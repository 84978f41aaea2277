# Writes OUT: the GLSL file NAME of DIR with every `#include "file"` line replaced by that file's
# text (from DIR), recursively, as gl::ShaderLibrary expands them before it compiles: a shader an
# engine compiles as it is, without Penumbra's include expansion (GLSL has no #include of its own).
# Run with cmake -P (cmake/Install.cmake): -DDIR=... -DNAME=... -DOUT=... -DVERSION=<Penumbra's>.
cmake_minimum_required(VERSION 3.20)  # the policies of a script run alone (IN_LIST)

# The text of `name` with its includes inlined, into `out_var`; `stack`: the files including it.
function(penumbra_flatten_glsl name out_var stack)
  if(name IN_LIST stack)
    message(FATAL_ERROR "FlattenGlsl.cmake: include cycle through ${name} (${stack})")
  endif()
  if(NOT EXISTS "${DIR}/${name}")
    message(FATAL_ERROR "FlattenGlsl.cmake: ${DIR}/${name} (included by ${stack}) does not exist")
  endif()
  list(APPEND stack ${name})
  file(READ "${DIR}/${name}" rest)
  set(rest "\n${rest}")  # every include line now starts after a newline
  set(done "")
  set(include_re "\n[ \t]*#[ \t]*include[ \t]+\"([^\"]+)\"[ \t]*\n")
  while(TRUE)
    string(REGEX MATCH "${include_re}" line "${rest}")
    if(line STREQUAL "")
      break()
    endif()
    set(included "${CMAKE_MATCH_1}")
    string(FIND "${rest}" "${line}" at)
    string(LENGTH "${line}" length)
    string(SUBSTRING "${rest}" 0 ${at} before)
    math(EXPR after "${at} + ${length} - 1")  # keep the line's closing newline for the next match
    string(SUBSTRING "${rest}" ${after} -1 rest)
    penumbra_flatten_glsl(${included} text "${stack}")
    string(APPEND done "${before}\n// ---- ${included} (inlined from Penumbra's renderer/shaders/) ----\n${text}// ---- end of ${included} ----")
  endwhile()
  string(APPEND done "${rest}")
  string(SUBSTRING "${done}" 1 -1 done)  # the newline added above
  set(${out_var} "${done}" PARENT_SCOPE)
endfunction()

penumbra_flatten_glsl(${NAME} text "")
set(header "// ${NAME} of Penumbra ${VERSION} (renderer/shaders/), its includes inlined by cmake/FlattenGlsl.cmake.
// Generated: do not edit. Compile it with `#version 450 core` and the defines it asks for before
// its text (docs/virtual-pages-in-your-engine.md); the C++ side of its bindings and buffers is
// <penumbra/shaders/virtual_mark_contract.h>.
")
file(WRITE ${OUT}.tmp "${header}${text}")
file(COPY_FILE ${OUT}.tmp ${OUT} ONLY_IF_DIFFERENT)
file(REMOVE ${OUT}.tmp)
