# ICP, occupancy fusion and the merge pipeline (server/voxel/merging.cmake).
mapd_add_test(voxel_merging_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/merge_test.cc
          ${CMAKE_CURRENT_LIST_DIR}/icp_test.cc
          ${CMAKE_CURRENT_LIST_DIR}/nearest_voxel_test.cc
          ${CMAKE_CURRENT_LIST_DIR}/cell_bits_test.cc
          ${CMAKE_CURRENT_LIST_DIR}/occupancy_fusion_test.cc
          ${CMAKE_CURRENT_LIST_DIR}/gravity_alignment_test.cc
          ${CMAKE_CURRENT_LIST_DIR}/correlation_search_test.cc
          ${CMAKE_CURRENT_LIST_DIR}/fft_support_test.cc
          ${CMAKE_CURRENT_LIST_DIR}/large_array_test.cc
          ${CMAKE_CURRENT_LIST_DIR}/yaw_refinement_test.cc
          ${CMAKE_CURRENT_LIST_DIR}/merge_hypotheses_test.cc
          ${CMAKE_CURRENT_LIST_DIR}/merge_lattice_test.cc
          ${CMAKE_CURRENT_LIST_DIR}/global_map_test.cc
          ${CMAKE_CURRENT_LIST_DIR}/map_edit_test.cc
          ${CMAKE_CURRENT_LIST_DIR}/merge_threads_test.cc
          ${CMAKE_CURRENT_LIST_DIR}/prepared_submap_test.cc
          ${CMAKE_CURRENT_LIST_DIR}/support/lattice_copy.cc
          ${CMAKE_CURRENT_LIST_DIR}/support/corridor_scene.cc
          ${CMAKE_CURRENT_LIST_DIR}/support/voxel_scene.cc
          ${CMAKE_CURRENT_LIST_DIR}/support/corner_scene.cc
  LIBS voxel ${OCTOMAP_LIBRARIES})
target_include_directories(voxel_merging_test SYSTEM PRIVATE ${OCTOMAP_INCLUDE_DIRS})

# The crop-and-move generator of the real-map merge benchmark (tests/bench/voxel_crops.h).
mapd_add_test(voxel_crops_test TEST_CODE
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/voxel_crops_test.cc ${PROJECT_SOURCE_DIR}/tests/bench/voxel_crops.cc
  LIBS voxel ${OCTOMAP_LIBRARIES})
target_include_directories(voxel_crops_test PRIVATE ${PROJECT_SOURCE_DIR}/tests)
target_include_directories(voxel_crops_test SYSTEM PRIVATE ${OCTOMAP_INCLUDE_DIRS})

# The merge on crops of the real maps, for cases the benchmark found (skipped
# without $MAPD_SHARED_DIR/data/octomap).
mapd_add_test(voxel_merge_real_map_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/merge_real_map_test.cc ${PROJECT_SOURCE_DIR}/tests/bench/voxel_crops.cc
          ${CMAKE_CURRENT_LIST_DIR}/support/lattice_copy.cc
  LIBS voxel ${OCTOMAP_LIBRARIES})
target_include_directories(voxel_merge_real_map_test PRIVATE ${PROJECT_SOURCE_DIR}/tests)
target_include_directories(voxel_merge_real_map_test SYSTEM PRIVATE ${OCTOMAP_INCLUDE_DIRS})
