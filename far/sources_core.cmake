target_sources(far_core PRIVATE src/error.cc)
