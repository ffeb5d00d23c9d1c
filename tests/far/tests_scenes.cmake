# far::scenes: the paper's workloads are valid, at the paper's scale, deterministic, and have
# contacts (checked by the brute-force reference of far::pairs on small instances).
far_add_test(far_scenes_test unit far/scenes/scenes_test.cc)
target_link_libraries(far_scenes_test PRIVATE far::scenes far::io far::pairs)
target_compile_definitions(far_scenes_test PRIVATE
                           FAR_BUNNY_OBJ="${PROJECT_SOURCE_DIR}/bench/data/bunny.obj")
