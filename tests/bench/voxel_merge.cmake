# Real-map merge benchmark (issue 4, item 7): our MergeSubmaps vs PCL FPFH +
# SampleConsensusPrerejective + ICP on crops of the shared OctoMap maps
# (writes the table for docs/voxel-merge.md). Not run by ctest.
add_executable(voxel_merge_bench
  ${CMAKE_CURRENT_LIST_DIR}/voxel_merge_bench.cc
  ${CMAKE_CURRENT_LIST_DIR}/voxel_crops.cc
  ${CMAKE_CURRENT_LIST_DIR}/fpfh_baseline.cc
  ${CMAKE_CURRENT_LIST_DIR}/mapd_merge_client.cc)
target_include_directories(voxel_merge_bench PRIVATE ${PROJECT_SOURCE_DIR}/tests)
target_include_directories(voxel_merge_bench SYSTEM PRIVATE ${OCTOMAP_INCLUDE_DIRS}
                           ${PCL_INCLUDE_DIRS})
target_link_libraries(voxel_merge_bench PRIVATE voxel mapd_proto ${OCTOMAP_LIBRARIES}
                      ${PCL_LIBRARIES})
# --mapd (no value): the mapd built beside it.
target_compile_definitions(voxel_merge_bench PRIVATE ${PCL_DEFINITIONS}
                           MAPD_BINARY="$<TARGET_FILE:mapd>")
mapd_set_warnings(voxel_merge_bench)
# GCC 12 reports a false -Warray-bounds inside Eigen's umeyama<float> (instantiated
# by PCL's registration headers), not in our code.
set_source_files_properties(${CMAKE_CURRENT_LIST_DIR}/fpfh_baseline.cc PROPERTIES
                            COMPILE_OPTIONS -Wno-array-bounds)

# The diagnostics replay the benchmark's trials (voxel_crops.h) through one
# part of the merge and print it against the ground truth.
function(mapd_add_voxel_diag name)
  add_executable(${name} ${CMAKE_CURRENT_FUNCTION_LIST_DIR}/${name}.cc
                         ${CMAKE_CURRENT_FUNCTION_LIST_DIR}/voxel_crops.cc)
  target_include_directories(${name} PRIVATE ${PROJECT_SOURCE_DIR}/tests)
  target_include_directories(${name} SYSTEM PRIVATE ${OCTOMAP_INCLUDE_DIRS})
  target_link_libraries(${name} PRIVATE voxel ${OCTOMAP_LIBRARIES})
  mapd_set_warnings(${name})
endfunction()
# The first corner solutions of each trial with their gate figures and true
# errors (how MergeParams' acceptance gates were chosen).
mapd_add_voxel_diag(voxel_hypotheses_diag)
# The correlation generator's levelling, yaws and translation peaks.
mapd_add_voxel_diag(voxel_correlation_diag)
# Every hypothesis's ICP residual, right apart from wrong (issue 42 item 2).
mapd_add_voxel_diag(voxel_residuals_diag)
# Not a diagnostic: the merges' CPU guard that deploy/test.sh runs after ctest.
mapd_add_voxel_diag(merge_cpu_guard)
