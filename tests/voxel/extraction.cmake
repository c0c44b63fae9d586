# Tests of part 1 of the voxel library (octree reader, voxel grid, corners).
# The real maps come from $MAPD_SHARED_DIR/data/octomap (skipped when absent).
mapd_add_test(voxel_extraction_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/octree_reader_test.cc
          ${CMAKE_CURRENT_LIST_DIR}/voxel_grid_test.cc
          ${CMAKE_CURRENT_LIST_DIR}/octree_leaves_test.cc
          ${CMAKE_CURRENT_LIST_DIR}/packed_key_set_test.cc
          ${CMAKE_CURRENT_LIST_DIR}/corner_extraction_test.cc
          ${CMAKE_CURRENT_LIST_DIR}/corner_components_test.cc
  LIBS voxel ${OCTOMAP_LIBRARIES})
target_include_directories(voxel_extraction_test SYSTEM PRIVATE ${OCTOMAP_INCLUDE_DIRS})
