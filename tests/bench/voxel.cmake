# Voxel benchmarks (docs/algorithms.md part B): corner extraction on the real OctoMap maps.
add_executable(voxel_corners_bench ${CMAKE_CURRENT_LIST_DIR}/voxel_corners_bench.cc)
target_link_libraries(voxel_corners_bench PRIVATE voxel)
mapd_set_warnings(voxel_corners_bench)

# Long-running soak against a real mapd (ingest, fusion, restarts, a frame
# tie by submap merge): ./soak_bench (figures in docs/long-running.md).
if(MAPD_WITH_SERVICE)
  add_executable(soak_bench soak_bench.cc ${PROJECT_SOURCE_DIR}/tests/common/octomap_scenes.cc)
  target_include_directories(soak_bench PRIVATE ${PROJECT_SOURCE_DIR}/tests ${PROJECT_SOURCE_DIR}/tests/service)
  target_include_directories(soak_bench SYSTEM PRIVATE ${OCTOMAP_INCLUDE_DIRS})
  target_link_libraries(soak_bench PRIVATE mapclient city_sim ${OCTOMAP_LIBRARIES} Threads::Threads)
  target_compile_definitions(soak_bench PRIVATE MAPD_BINARY="$<TARGET_FILE:mapd>")
  mapd_set_warnings(soak_bench)
endif()
