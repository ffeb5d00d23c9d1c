# Sources of this area are added here with target_sources(far_core PRIVATE ...).
