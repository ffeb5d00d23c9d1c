# far_add_area(io <sources...>) and this area's dependencies.
