# far_add_area(offsets <sources...>) and this area's dependencies.
