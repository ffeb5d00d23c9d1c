# far_pairs: object-level sweep-and-prune and the exact stage (triangle pairs of object pairs).
far_add_area(pairs src/pairs/sweep_and_prune.cc src/pairs/exact_stage.cc)
target_link_libraries(far_pairs PUBLIC far_geometry)
