# far_add_area(offsets <sources...>) and this area's dependencies.
far_add_area(offsets
  src/offsets/bounding_offset.cc
  src/offsets/obb.cc
  src/offsets/triangle_frame.cc
  src/offsets/triangle_offsets.cc)
