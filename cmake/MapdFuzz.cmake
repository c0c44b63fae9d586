# MAPD_BUILD_FUZZ: every target gets libFuzzer's coverage instrumentation and
# ASan + UBSan, so the fuzzer sees (and checks) the library code it drives;
# only the fuzz targets themselves link libFuzzer's main (mapd_add_fuzzer).
if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
  message(FATAL_ERROR "MAPD_BUILD_FUZZ needs clang (libFuzzer): configure with "
                      "-DCMAKE_CXX_COMPILER=clang++-14 (Debian: clang-14, libclang-rt-14-dev)")
endif()
if(NOT MAPD_WITH_SERVICE)
  message(FATAL_ERROR "MAPD_BUILD_FUZZ needs MAPD_WITH_SERVICE=ON (the batch and config targets)")
endif()
add_compile_options(-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=undefined
                    -fno-omit-frame-pointer)
add_link_options(-fsanitize=address,undefined)

# mapd_add_fuzzer(NAME SOURCES a.cc LIBS lib1): one libFuzzer binary.
function(mapd_add_fuzzer name)
  cmake_parse_arguments(ARG "" "" "SOURCES;LIBS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_LIBS})
  target_link_options(${name} PRIVATE -fsanitize=fuzzer)
  mapd_set_warnings(${name})
endfunction()
