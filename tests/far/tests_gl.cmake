# GPU tests: headless GL (llvmpipe in CI). Label gpu.
far_add_test(far_gl_test gpu far/gl/gl_context_test.cc)
target_link_libraries(far_gl_test PRIVATE far::gl)
