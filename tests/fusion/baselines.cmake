# The Fuser interface, the competing methods and the scenario generator.
mapd_add_test(fusion_baselines_test TEST_CODE
  SOURCES baselines_test.cc
  LIBS mapd_eval)
