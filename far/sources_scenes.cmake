# Demo and test scene generators (far/scenes.h).
far_add_area(scenes src/scenes/scenes.cc)
target_link_libraries(far_scenes PUBLIC far_io)
