# mesolab_embed_shaders(TARGET <target> BASE_DIR <dir> FILES <file>...)
#
# Embeds shader files into <target> at build time, as the table behind gpu/shaders.h. Adds one
# generated source, <binary dir>/<target>_embedded_shaders.cpp, to <target>; it is regenerated
# by embed_shaders.cmake whenever a listed file or the script changes, and only rewritten when
# its content changes. Relative FILES and BASE_DIR are taken from CMAKE_CURRENT_SOURCE_DIR; every
# file must lie under BASE_DIR, and is named by its path relative to it ("shaders/common.glsl").
# Call it once per target. When FILES comes from file(GLOB), use CONFIGURE_DEPENDS so that new
# shader files are picked up without re-running cmake by hand.
#
# The target also needs gpu/shaders.cpp (the reader) and the repository root on its include
# path (the generated file includes "gpu/shader_table.h").

set(_MESOLAB_EMBED_SHADERS_SCRIPT "${CMAKE_CURRENT_LIST_DIR}/embed_shaders.cmake")

function(mesolab_embed_shaders)
  cmake_parse_arguments(PARSE_ARGV 0 ARG "" "TARGET;BASE_DIR" "FILES")
  if(ARG_UNPARSED_ARGUMENTS)
    message(FATAL_ERROR "mesolab_embed_shaders: unexpected arguments: ${ARG_UNPARSED_ARGUMENTS}")
  endif()
  if(NOT ARG_TARGET OR NOT TARGET "${ARG_TARGET}")
    message(FATAL_ERROR "mesolab_embed_shaders: TARGET must name an existing target (got '${ARG_TARGET}')")
  endif()
  if(NOT ARG_BASE_DIR)
    message(FATAL_ERROR "mesolab_embed_shaders: BASE_DIR is required")
  endif()
  get_target_property(already "${ARG_TARGET}" MESOLAB_EMBEDDED_SHADERS)
  if(already)
    message(FATAL_ERROR "mesolab_embed_shaders: called twice for target ${ARG_TARGET}")
  endif()

  get_filename_component(base "${ARG_BASE_DIR}" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_SOURCE_DIR}")
  set(files "")
  foreach(file IN LISTS ARG_FILES)
    get_filename_component(abs "${file}" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_SOURCE_DIR}")
    file(RELATIVE_PATH rel "${base}" "${abs}")
    if(rel MATCHES "^\\.\\./" OR IS_ABSOLUTE "${rel}")
      message(FATAL_ERROR "mesolab_embed_shaders: ${abs} is not under BASE_DIR ${base}")
    endif()
    list(APPEND files "${abs}")
  endforeach()
  list(REMOVE_DUPLICATES files)
  list(SORT files)
  list(LENGTH files count)

  # The stamp is the rule's real output; the generated .cpp is a byproduct that keeps its old
  # timestamp when its content did not change, so nothing recompiles after a mere touch.
  set(out "${CMAKE_CURRENT_BINARY_DIR}/${ARG_TARGET}_embedded_shaders.cpp")
  set(stamp "${CMAKE_CURRENT_BINARY_DIR}/${ARG_TARGET}_embedded_shaders.stamp")
  add_custom_command(
    OUTPUT "${stamp}"
    BYPRODUCTS "${out}"
    COMMAND "${CMAKE_COMMAND}" "-DOUTPUT=${out}" "-DBASE_DIR=${base}"
            -P "${_MESOLAB_EMBED_SHADERS_SCRIPT}" -- ${files}
    COMMAND "${CMAKE_COMMAND}" -E touch "${stamp}"
    DEPENDS ${files} "${_MESOLAB_EMBED_SHADERS_SCRIPT}"
    COMMENT "Embedding ${count} shader files into ${ARG_TARGET}"
    VERBATIM)
  target_sources("${ARG_TARGET}" PRIVATE "${out}" "${stamp}")
  set_target_properties("${ARG_TARGET}" PROPERTIES MESOLAB_EMBEDDED_SHADERS "${files}")
endfunction()
