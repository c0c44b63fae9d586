# Corner matching and alignment (docs/algorithms.md B.4, B.5): pure Eigen.
list(APPEND VOXEL_SOURCES
  ${CMAKE_CURRENT_LIST_DIR}/max_clique.cc
  ${CMAKE_CURRENT_LIST_DIR}/rigid_fit.cc
  ${CMAKE_CURRENT_LIST_DIR}/corner_candidates.cc
  ${CMAKE_CURRENT_LIST_DIR}/corner_matching.cc
)
