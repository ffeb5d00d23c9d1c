# Headless GL and the GPU culling passes. GL/EGL stay private: no GL type in a public header.
find_package(PkgConfig REQUIRED)
pkg_check_modules(EPOXY REQUIRED IMPORTED_TARGET epoxy)
far_add_area(gl src/gl/gl_context.cc)
target_link_libraries(far_gl PUBLIC far_offsets PRIVATE PkgConfig::EPOXY)
