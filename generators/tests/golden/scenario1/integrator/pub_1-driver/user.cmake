# Your additions to the build of pub_1_driver: libraries of your sensors,
# extra sources, install rules. `modd generate` wrote this file once and will
# never overwrite it. Example:
#   find_package(PkgConfig REQUIRED)
#   pkg_check_modules(I2C REQUIRED libi2c)
#   target_link_libraries(pub_1_driver PRIVATE ${I2C_LIBRARIES})
