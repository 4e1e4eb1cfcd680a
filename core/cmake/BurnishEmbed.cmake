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

# burnish_embed_table(TARGET <target> FILES <paths...> SYMBOL <name> DIR <label>)
# Compiles many text resources into <target> as one table sorted by file name:
#   namespace burnish::resources {
#     extern const std::pair<std::string_view, std::string_view> <name>[]; // {file name, contents}
#     extern const int <name>Count; }
# The table is regenerated when any file changes (callers glob with CONFIGURE_DEPENDS, so added or
# removed files re-run CMake).
function(burnish_embed_table)
  cmake_parse_arguments(ARG "" "TARGET;SYMBOL;DIR" "FILES" ${ARGN})
  set(out "${CMAKE_CURRENT_BINARY_DIR}/embedded/${ARG_SYMBOL}.cpp")
  string(REPLACE ";" "|" files "${ARG_FILES}")
  add_custom_command(
    OUTPUT "${out}"
    COMMAND ${CMAKE_COMMAND} "-DFILES=${files}" -DOUT=${out} -DSYMBOL=${ARG_SYMBOL} -DDIR=${ARG_DIR}
            -P "${PROJECT_SOURCE_DIR}/core/cmake/BurnishEmbedTableRun.cmake"
    DEPENDS ${ARG_FILES} "${PROJECT_SOURCE_DIR}/core/cmake/BurnishEmbedTableRun.cmake"
    COMMENT "Embedding ${ARG_DIR}"
    VERBATIM)
  target_sources(${ARG_TARGET} PRIVATE "${out}")
endfunction()
