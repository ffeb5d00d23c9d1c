# far_geometry: exact predicates and triangle-triangle tests (intersection, distance).
# The predicates' floating-point filters assume every a*b+c is rounded twice: never let the
# compiler contract it into an fma (and never build these with -ffast-math).
set(FAR_GEOMETRY_SOURCES
    src/geometry/predicates.cc
    src/geometry/triangle_intersection.cc
    src/geometry/triangle_distance.cc)
far_add_area(geometry ${FAR_GEOMETRY_SOURCES})
set_source_files_properties(${FAR_GEOMETRY_SOURCES} PROPERTIES COMPILE_OPTIONS "-ffp-contract=off")
