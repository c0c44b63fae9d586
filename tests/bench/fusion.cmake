# Fusion benchmark: the paper's comparison on the synthetic scenario, and the
# speed targets. Run by hand (not a ctest): ./fusion_bench --svg-dir ../docs
add_executable(fusion_bench fusion_bench.cc)
target_link_libraries(fusion_bench PRIVATE mapd_eval)
mapd_set_warnings(fusion_bench)
