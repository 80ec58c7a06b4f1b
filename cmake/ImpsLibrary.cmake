# SPDX-License-Identifier: MIT
# imps_library(NAME SOURCES...): the static library of one module folder, `imps_NAME` with the alias `imps::NAME`
# (the core, NAME `imps`, is target `imps`), its public headers include/<folder>/ beside the calling CMakeLists.txt
# on the include path, the project's warnings at build time only, and `cmake --install` of the library and its
# headers into the export set impsTargets, which the top-level CMakeLists.txt exports as the package `imps`.
function(imps_library name)
  if(name STREQUAL "imps")
    set(target imps)
  else()
    set(target imps_${name})
  endif()
  add_library(${target} ${ARGN})
  add_library(imps::${name} ALIAS ${target})
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${name})
  target_include_directories(${target} PUBLIC $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
                                              $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  target_link_libraries(${target} PRIVATE $<BUILD_INTERFACE:imps_warnings>)
  install(TARGETS ${target} EXPORT impsTargets ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
  install(DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR}/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
endfunction()
