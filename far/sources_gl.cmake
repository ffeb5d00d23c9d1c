# Headless GL, the GPU culling passes and the step pipeline. GL, EGL and FCL stay private: no
# such type appears in a public header.
find_package(PkgConfig REQUIRED)
pkg_check_modules(EPOXY REQUIRED IMPORTED_TARGET epoxy)
find_package(fcl REQUIRED)
far_add_area(gl src/gl/gl_context.cc src/gl/gl_program.cc src/gl/culling_renderer.cc
             src/pipeline/pipeline.cc src/pipeline/fcl_collider.cc)
target_link_libraries(far_gl PUBLIC far_offsets far_pairs far_io PRIVATE PkgConfig::EPOXY fcl)
