# far::model: the scene rules, the request check and the quantile every layer shares.
far_add_test(far_model_test unit far/model/scene_model_test.cc far/model/scene_at_step_test.cc
             far/model/step_request_test.cc far/model/slot_ids_test.cc
             far/model/scene_budget_test.cc)
target_link_libraries(far_model_test PRIVATE far::model)
