# far_add_area(geometry <sources...>) and this area's dependencies.
