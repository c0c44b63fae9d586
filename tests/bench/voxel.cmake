# Voxel benchmarks (ALGORITHMS.md B): corner extraction on the real OctoMap maps.
add_executable(voxel_corners_bench ${CMAKE_CURRENT_LIST_DIR}/voxel_corners_bench.cc)
target_link_libraries(voxel_corners_bench PRIVATE voxel)
mapd_set_warnings(voxel_corners_bench)
