# Part 1 of the voxel library: corner extraction (docs/algorithms.md B.1-B.3).
# Included by CMakeLists.txt.
list(APPEND VOXEL_SOURCES
  ${CMAKE_CURRENT_LIST_DIR}/corner_window.cc
  ${CMAKE_CURRENT_LIST_DIR}/corner_voxel_index.cc
  ${CMAKE_CURRENT_LIST_DIR}/normals_grid.cc
  ${CMAKE_CURRENT_LIST_DIR}/plane_regions.cc
  ${CMAKE_CURRENT_LIST_DIR}/corner_faces.cc
  ${CMAKE_CURRENT_LIST_DIR}/corner_extraction.cc
)
