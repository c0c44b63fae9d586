# Real laser logs (shared/data/laser) through the fusion engine: ./laser_bench
# (issue item 9; figures in docs/fusion-real-data.md). Run on demand, not by ctest.
find_package(ZLIB REQUIRED)
add_executable(laser_bench laser_bench.cc carmen.cc seen_through.cc)
target_include_directories(laser_bench PRIVATE ${PROJECT_SOURCE_DIR}/tests)
target_link_libraries(laser_bench PRIVATE fusion robot_datasets)
target_compile_definitions(laser_bench PRIVATE MAPD_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
mapd_set_warnings(laser_bench)

# Bounded against exact fusion on the synthetic city and the laser logs:
# ./fusion_modes_bench (figures in docs/long-running.md). On demand.
if(MAPD_WITH_SERVICE)  # it links the service and the client library
  add_executable(fusion_modes_bench fusion_modes_bench.cc carmen.cc)
  target_include_directories(fusion_modes_bench PRIVATE ${PROJECT_SOURCE_DIR}/tests)
  target_link_libraries(fusion_modes_bench PRIVATE fusion robot_datasets mapd_eval service mapclient)
  target_compile_definitions(fusion_modes_bench PRIVATE MAPD_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
  mapd_set_warnings(fusion_modes_bench)
endif()

# The robot library's laser extractor on the same logs: CPU per scan and per
# beam, lines per scan (docs/robot-library.md). On demand.
add_executable(robot_extraction_bench robot_extraction_bench.cc carmen.cc)
target_include_directories(robot_extraction_bench PRIVATE ${PROJECT_SOURCE_DIR}/tests)
target_link_libraries(robot_extraction_bench PRIVATE robot_datasets)
target_compile_definitions(robot_extraction_bench PRIVATE MAPD_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
mapd_set_warnings(robot_extraction_bench)
