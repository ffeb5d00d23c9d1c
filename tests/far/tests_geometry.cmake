# Geometry area: exact predicates and triangle tests, checked against an exact rational
# reference (GMP, tests only: the library itself never links GMP).
find_path(FAR_GMPXX_INCLUDE_DIR gmpxx.h REQUIRED)
find_library(FAR_GMPXX_LIBRARY gmpxx REQUIRED)
find_library(FAR_GMP_LIBRARY gmp REQUIRED)

# far_hard_cases: the exact reference (mpq_class) and the hard-case suite, shared by the tests,
# the FCL comparison benchmark and later GPU tests.
add_library(far_hard_cases STATIC far/geometry/exact_reference.cc far/geometry/hard_cases.cc)
target_include_directories(far_hard_cases PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/far/geometry
                                                 ${FAR_GMPXX_INCLUDE_DIR})
target_link_libraries(far_hard_cases PUBLIC far_geometry ${FAR_GMPXX_LIBRARY} ${FAR_GMP_LIBRARY}
                                     PRIVATE far_warnings)

far_add_test(far_geometry_test unit
  far/geometry/predicates_test.cc
  far/geometry/exact_reference_test.cc
  far/geometry/triangle_intersection_test.cc
  far/geometry/triangle_distance_test.cc
  far/geometry/triangle_contact_test.cc)
target_link_libraries(far_geometry_test PRIVATE far::geometry far_hard_cases)
