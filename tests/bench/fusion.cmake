# Fusion benchmark: the paper's comparison on the synthetic scenario, and the
# speed targets. Run by hand (not a ctest): ./fusion_bench --svg-dir ../docs
# Its SVG pictures are drawn by cairo (eval_svg), so it is built with client/.
if(TARGET eval_svg)
  add_executable(fusion_bench fusion_bench.cc)
  target_link_libraries(fusion_bench PRIVATE eval_svg)
  mapd_set_warnings(fusion_bench)
endif()

# Throughput of FusionEngine::Add on a synthetic block world (fusion library
# only): ./fusion_throughput [FEATURES]
add_executable(fusion_throughput fusion_throughput.cc)
target_link_libraries(fusion_throughput PRIVATE fusion)
mapd_set_warnings(fusion_throughput)

# CPU guard (issue 40): fused features per CPU-second on the soak's city with
# free-space evidence on; fails below half the figure of docs/long-running.md.
# Run by deploy/test.sh after ctest (not a ctest: see the program's header).
add_executable(fusion_cpu_guard fusion_cpu_guard.cc)
target_link_libraries(fusion_cpu_guard PRIVATE city_sim)
mapd_set_warnings(fusion_cpu_guard)

# Adversarial workloads (issue 46): fused features per CPU-second and the
# slowest observation for hostile but valid input, next to the revisited
# floor: ./fusion_adversarial_bench [--workload NAME]
add_executable(fusion_adversarial_bench fusion_adversarial_bench.cc)
target_link_libraries(fusion_adversarial_bench PRIVATE fusion)
mapd_set_warnings(fusion_adversarial_bench)

# The fuser's stall per snapshot on a real state (a soak's database):
# ./snapshot_bench DB [RUNS]
if(TARGET storage_sqlite)
  add_executable(snapshot_bench snapshot_bench.cc)
  target_link_libraries(snapshot_bench PRIVATE fusion storage_sqlite)
  mapd_set_warnings(snapshot_bench)
endif()
