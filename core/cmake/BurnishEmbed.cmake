# burnish_embed(TARGET <target> FILE <path> SYMBOL <name>)
# Compiles a text resource into <target> as
#   namespace burnish::resources { extern const std::string_view <name>; }
# so the built-in defaults need no files at run time. The file is re-embedded when it changes.
function(burnish_embed)
  cmake_parse_arguments(ARG "" "TARGET;FILE;SYMBOL" "" ${ARGN})
  set(out "${CMAKE_CURRENT_BINARY_DIR}/embedded/${ARG_SYMBOL}.cpp")
  add_custom_command(
    OUTPUT "${out}"
    COMMAND ${CMAKE_COMMAND} -DIN=${ARG_FILE} -DOUT=${out} -DSYMBOL=${ARG_SYMBOL}
            -P "${PROJECT_SOURCE_DIR}/core/cmake/BurnishEmbedRun.cmake"
    DEPENDS "${ARG_FILE}" "${PROJECT_SOURCE_DIR}/core/cmake/BurnishEmbedRun.cmake"
    COMMENT "Embedding ${ARG_FILE}"
    VERBATIM)
  target_sources(${ARG_TARGET} PRIVATE "${out}")
endfunction()
