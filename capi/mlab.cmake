# The mlab C library for a CMake project, built by cargo from mlab's source tree:
#
#   include(path/to/mlab/capi/mlab.cmake)
#   target_link_libraries(my_renderer PRIVATE mlab::mlab)   # mlab.h and mlab.hpp, static library
#
# Every build runs `cargo build --release -p mlab-capi` before linking (cargo rebuilds the
# library when a source changed and returns at once when none did), and the program is relinked
# when the archive changed. The archive is where cargo puts it: CARGO_TARGET_DIR when it is set
# at configure time (relative to mlab's root), otherwise mlab's target/.
cmake_minimum_required(VERSION 3.18)
get_filename_component(MLAB_ROOT "${CMAKE_CURRENT_LIST_DIR}/.." ABSOLUTE)
if(DEFINED ENV{CARGO_TARGET_DIR})
  get_filename_component(MLAB_CARGO_TARGET_DIR "$ENV{CARGO_TARGET_DIR}" ABSOLUTE BASE_DIR "${MLAB_ROOT}")
else()
  set(MLAB_CARGO_TARGET_DIR "${MLAB_ROOT}/target")
endif()
set(MLAB_ARCHIVE "${MLAB_CARGO_TARGET_DIR}/release/libmlab_capi.a")
find_program(MLAB_CARGO cargo REQUIRED)
add_custom_target(mlab_cargo
  COMMAND "${CMAKE_COMMAND}" -E env "CARGO_TARGET_DIR=${MLAB_CARGO_TARGET_DIR}"
          "${MLAB_CARGO}" build --release -p mlab-capi
  WORKING_DIRECTORY "${MLAB_ROOT}"
  BYPRODUCTS "${MLAB_ARCHIVE}"
  COMMENT "cargo build --release -p mlab-capi"
  VERBATIM)
add_library(mlab::mlab STATIC IMPORTED GLOBAL)
add_dependencies(mlab::mlab mlab_cargo)
# The system libraries the Rust standard library needs on Linux (docs/c.md).
set_target_properties(mlab::mlab PROPERTIES
  IMPORTED_LOCATION "${MLAB_ARCHIVE}"
  INTERFACE_INCLUDE_DIRECTORIES "${MLAB_ROOT}/capi/include"
  INTERFACE_LINK_LIBRARIES "gcc_s;util;rt;pthread;m;dl")
