# Corner matching: maximum clique vs the paper's backtracking (writes docs/voxel-matching.md).
if(MAPD_WITH_VOXEL)
  add_executable(voxel_matching_bench
    ${CMAKE_CURRENT_LIST_DIR}/voxel_matching_bench.cc
    ${PROJECT_SOURCE_DIR}/tests/voxel/support/corner_scene.cc)
  target_include_directories(voxel_matching_bench PRIVATE ${PROJECT_SOURCE_DIR}/tests)
  target_link_libraries(voxel_matching_bench PRIVATE voxel_eval)
  target_compile_definitions(voxel_matching_bench PRIVATE MAPD_DOCS_DIR="${PROJECT_SOURCE_DIR}/docs")
  mapd_set_warnings(voxel_matching_bench)
endif()
