# Planes from a simulated 16-beam LiDAR (tests/sim) in the synthetic city and
# the real OctoMap maps, through ProjectToGround and fusion (issue 10):
# ./plane_bench [--data DIR] (figures in docs/planes-3d.md). On demand, not by ctest.
# Its SVG pictures are drawn by cairo (eval_svg), so it is built with client/.
if(TARGET eval_svg AND TARGET lidar_sim)
  add_executable(plane_bench ${CMAKE_CURRENT_LIST_DIR}/plane_bench.cc)
  target_include_directories(plane_bench PRIVATE ${PROJECT_SOURCE_DIR}/tests)
  target_link_libraries(plane_bench PRIVATE lidar_sim mapd_eval eval_svg)
  target_compile_definitions(plane_bench PRIVATE MAPD_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
  mapd_set_warnings(plane_bench)
endif()

# The robot library's plane extractor: RANSAC against region growing,
# organised against unorganised, on simulated city scans (known surfaces) and
# the shared real 3D scan: ./cloud_planes_bench [--data DIR] [--city-step M]
# (figures in docs/robot-library.md). On demand, not by ctest.
if(TARGET lidar_sim)
  add_executable(cloud_planes_bench ${CMAKE_CURRENT_LIST_DIR}/cloud_planes_bench.cc)
  target_include_directories(cloud_planes_bench PRIVATE ${PROJECT_SOURCE_DIR}/tests)
  target_link_libraries(cloud_planes_bench PRIVATE lidar_sim robot_planes)
  target_compile_definitions(cloud_planes_bench PRIVATE MAPD_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
  mapd_set_warnings(cloud_planes_bench)
endif()
