# mapd_optimize_in_debug(target): with MAPD_DEBUG_OPTIMIZE_HOT on, compiles the
# target at -O1 in Debug builds. For the code the tests spend their time in
# (the fusion core and its tests, whose property and bounded-engine tests
# replay thousands of scans through the engine and a batch reference): at -O0
# every Eigen expression is a chain of out-of-line calls, and under ASan the
# fusion property test took 45 s on one seed, 2.6 s at -O1. -O1 is what the
# ASan documentation recommends for speed; the asan-ubsan preset turns it on
# (the tsan preset builds everything at -O1).
function(mapd_optimize_in_debug target)
  if(MAPD_DEBUG_OPTIMIZE_HOT)
    target_compile_options(${target} PRIVATE $<$<CONFIG:Debug>:-O1>)
  endif()
endfunction()
