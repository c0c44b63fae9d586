# Part 3 of the voxel library: ICP, overlap score, occupancy fusion and the
# merge pipeline (docs/algorithms.md B.5-B.7). Included by CMakeLists.txt.
list(APPEND VOXEL_SOURCES
  ${CMAKE_CURRENT_LIST_DIR}/nearest_voxel.cc
  ${CMAKE_CURRENT_LIST_DIR}/icp.cc
  ${CMAKE_CURRENT_LIST_DIR}/lattice_pose.cc
  ${CMAKE_CURRENT_LIST_DIR}/merge_overlap.cc
  ${CMAKE_CURRENT_LIST_DIR}/occupancy_fusion.cc
  ${CMAKE_CURRENT_LIST_DIR}/merge_graph.cc
  ${CMAKE_CURRENT_LIST_DIR}/gravity_alignment.cc
  ${CMAKE_CURRENT_LIST_DIR}/large_array.cc
  ${CMAKE_CURRENT_LIST_DIR}/fft_support.cc
  ${CMAKE_CURRENT_LIST_DIR}/correlation_search.cc
  ${CMAKE_CURRENT_LIST_DIR}/yaw_refinement.cc
  ${CMAKE_CURRENT_LIST_DIR}/submap_features.cc
  ${CMAKE_CURRENT_LIST_DIR}/merge_hypotheses.cc
  ${CMAKE_CURRENT_LIST_DIR}/merge_pair.cc
  ${CMAKE_CURRENT_LIST_DIR}/merge_params.cc
  ${CMAKE_CURRENT_LIST_DIR}/merge.cc
  ${CMAKE_CURRENT_LIST_DIR}/merge_evidence.cc
  ${CMAKE_CURRENT_LIST_DIR}/global_map.cc
)
