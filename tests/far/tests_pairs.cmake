# far_pairs: sweep-and-prune and the exact stage, each against a brute-force reference.
far_add_test(far_pairs_test unit far/pairs/sweep_and_prune_test.cc
             far/pairs/exact_stage_test.cc far/pairs/bvh_stage_test.cc
             far/pairs/stage_stop_test.cc far/pairs/pair_sort_test.cc
             far/pairs/float_bounds_test.cc far/pairs/penetration_test.cc)
target_link_libraries(far_pairs_test PRIVATE far::pairs far::scenes)
