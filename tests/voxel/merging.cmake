# ICP, occupancy fusion and the merge pipeline (server/voxel/merging.cmake).
mapd_add_test(voxel_merging_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/merge_test.cc
          ${CMAKE_CURRENT_LIST_DIR}/icp_test.cc
          ${CMAKE_CURRENT_LIST_DIR}/occupancy_fusion_test.cc
          ${CMAKE_CURRENT_LIST_DIR}/support/voxel_scene.cc
          ${CMAKE_CURRENT_LIST_DIR}/support/corner_scene.cc
  LIBS voxel ${OCTOMAP_LIBRARIES})
target_include_directories(voxel_merging_test SYSTEM PRIVATE ${OCTOMAP_INCLUDE_DIRS})
