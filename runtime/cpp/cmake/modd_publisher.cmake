# Adds the target `modd_publisher` (the MoDD C++ publisher client) to an
# integrator's CMake project. Standard library and POSIX threads only.
#
#   include(/path/to/runtime/cpp/cmake/modd_publisher.cmake)
#   target_link_libraries(my_driver PRIVATE modd_publisher)
get_filename_component(_MODD_CPP_DIR "${CMAKE_CURRENT_LIST_DIR}/.." ABSOLUTE)
if(NOT TARGET modd_publisher)
  find_package(Threads REQUIRED)
  add_library(modd_publisher STATIC ${_MODD_CPP_DIR}/src/client/publisher.cpp)
  target_include_directories(modd_publisher PUBLIC ${_MODD_CPP_DIR}/include)
  target_compile_features(modd_publisher PUBLIC cxx_std_20)
  target_link_libraries(modd_publisher PUBLIC Threads::Threads)
endif()
