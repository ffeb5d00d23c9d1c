# Scene generators shared by the GPU tests and the studies.
add_library(far_test_scenes STATIC support/test_scenes.cc)
target_include_directories(far_test_scenes PUBLIC support)
target_link_libraries(far_test_scenes PUBLIC far::pairs far::scenes PRIVATE far_warnings)

# GPU tests: headless GL (llvmpipe in CI). Label gpu.
far_add_test(far_gpu_test gpu far/gpu/gl_context_test.cc far/gpu/snapshot_test.cc
             far/gpu/gl_lock_test.cc far/gpu/compute_collider_test.cc
             far/gpu/compute_batcher_test.cc
             far/pipeline/pipeline_culling_test.cc
             far/pipeline/certificate_test.cc far/pipeline/gl_deadline_test.cc
             far/pipeline/gpu_cost_test.cc)
target_link_libraries(far_gpu_test PRIVATE far::pipeline far::io far_test_scenes far_hard_cases)


# With no EGL driver at all (GLVND pointed at no vendor), far-daemon exits with one clear line
# that lists what it tried, instead of crashing.
add_test(NAME GlContextTest.NoDriverGivesAClearErrorNamingWhatWasTried
         COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/far/gpu/no_driver_test.sh $<TARGET_FILE:far-daemon>)
set_tests_properties(GlContextTest.NoDriverGivesAClearErrorNamingWhatWasTried PROPERTIES LABELS gpu)

# deploy/gl-renderer.sh (gpu-run.sh's first check on a GPU machine) reads the renderer from the
# daemon's ready line as the daemon writes it today; it once stopped matching when the line
# gained fields, and every GPU run would have stopped at "no OpenGL context".
add_test(NAME GpuRunTest.GlRendererReadsTheDaemonsReadyLine
         COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/far/gpu/gl_renderer_test.sh
                 ${PROJECT_SOURCE_DIR}/deploy/gl-renderer.sh $<TARGET_FILE:far-daemon>)
set_tests_properties(GpuRunTest.GlRendererReadsTheDaemonsReadyLine PROPERTIES LABELS gpu)

# --gl-platform device on a machine without a GPU: a clear error, never llvmpipe. Skipped (77)
# where a hardware EGL device exists.
add_test(NAME GlContextTest.DevicePlatformWithoutAGpuIsAnErrorNotLlvmpipe
         COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/far/gpu/device_platform_test.sh
                 ${PROJECT_SOURCE_DIR}/deploy/gl-renderer.sh $<TARGET_FILE:far-daemon>)
set_tests_properties(GlContextTest.DevicePlatformWithoutAGpuIsAnErrorNotLlvmpipe PROPERTIES
                     LABELS gpu SKIP_RETURN_CODE 77)

# The draw pacer's bound on a piece's screen area: a pure function in a header private to
# far::gpu, tested through it (no GL).
far_add_test(far_piece_footprint_test unit far/gpu/piece_footprint_test.cc)
target_include_directories(far_piece_footprint_test PRIVATE ${PROJECT_SOURCE_DIR}/far/gpu/src)
target_link_libraries(far_piece_footprint_test PRIVATE far::gpu)
far_add_test(far_placement_probe_test unit far/gpu/placement_probe_test.cc)
target_include_directories(far_placement_probe_test PRIVATE ${PROJECT_SOURCE_DIR}/far/gpu/src)
target_link_libraries(far_placement_probe_test PRIVATE far::gpu)
