# far_add_test(<name> <label> <sources...>) for this area.
