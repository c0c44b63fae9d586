# Corner matching and alignment (server/voxel/matching.cmake).
mapd_add_test(voxel_matching_test
  SOURCES ${CMAKE_CURRENT_LIST_DIR}/matching_test.cc
          ${CMAKE_CURRENT_LIST_DIR}/max_clique_test.cc
          ${CMAKE_CURRENT_LIST_DIR}/rigid_fit_test.cc
          ${CMAKE_CURRENT_LIST_DIR}/support/corner_scene.cc
          ${CMAKE_CURRENT_LIST_DIR}/support/ply_reader.cc
  LIBS voxel_eval)
