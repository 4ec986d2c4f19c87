# check_includes.cmake: protocols/ never include daemon/ (ARCHITECTURE.md, "The layers"):
# each protocol declares the service interface it needs and the daemon
# hands it an implementation. Run by the build (cmake -P, before fm_http and
# fm_modbus compile): every quoted #include in protocols/ must name a file in
# protocols/ (beside the including file, or from the project root) or in
# lib/; anything else, daemon/ above all, stops the build with its place.
# Usage: cmake -DROOT=<source dir> -DSTAMP=<file> -P check_includes.cmake
file(GLOB_RECURSE sources ${ROOT}/protocols/*.c ${ROOT}/protocols/*.h)
set(bad "")
foreach(src ${sources})
  file(STRINGS ${src} lines REGEX "^[ \t]*#[ \t]*include[ \t]*\"")
  get_filename_component(here ${src} DIRECTORY)
  foreach(line ${lines})
    string(REGEX REPLACE "^[ \t]*#[ \t]*include[ \t]*\"([^\"]*)\".*" "\\1" name "${line}")
    if(name MATCHES "^daemon/" OR name MATCHES "\\.\\./")
      list(APPEND bad "${src}: #include \"${name}\"")
    elseif(EXISTS ${here}/${name} OR EXISTS ${ROOT}/lib/${name})
    elseif(name MATCHES "^protocols/" AND EXISTS ${ROOT}/${name})
    else()
      list(APPEND bad "${src}: #include \"${name}\" (not in protocols/ or lib/)")
    endif()
  endforeach()
endforeach()
if(bad)
  string(REPLACE ";" "\n  " bad "${bad}")
  message(FATAL_ERROR "protocols/ must not include the daemon (ARCHITECTURE.md sec. 1, The layers):\n  ${bad}")
endif()
file(WRITE ${STAMP} "ok\n")
