# far_pipeline: the pipeline's CPU methods (no GL): the FCL baseline against FCL itself and the
# exact reference. FCL is linked to call its own triangle test on the pairs that differ.
find_package(fcl REQUIRED)
far_add_test(far_pipeline_test unit far/pipeline/fcl_baseline_test.cc far/pipeline/auto_selector_test.cc
             far/pipeline/step_control_test.cc
             far/pipeline/pose_normalization_test.cc far/pipeline/world_coordinates_test.cc
             far/pipeline/cpu_culls_test.cc far/pipeline/slots_test.cc
             far/pipeline/cpu_cores_test.cc far/pipeline/geometry_stage_test.cc)
target_link_libraries(far_pipeline_test PRIVATE far::pipeline far::scenes far_test_scenes fcl)
