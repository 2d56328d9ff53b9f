# Shared build helpers: warnings on every project target, one helper to add a test, one to
# install a library with its headers into the exported CMake package (upd_nav, namespace upd::).
include(GNUInstallDirs)

function(upd_set_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow=local
                                           -Wno-deprecated-copy)
endfunction()

# upd_add_test(NAME name SOURCES a.cpp b.cpp LIBS lib1 lib2)
function(upd_add_test)
  cmake_parse_arguments(T "" "NAME" "SOURCES;LIBS" ${ARGN})
  add_executable(${T_NAME} ${T_SOURCES})
  target_link_libraries(${T_NAME} PRIVATE ${T_LIBS} GTest::gtest GTest::gtest_main)
  target_compile_definitions(${T_NAME} PRIVATE
    UPD_SHARED_DATA_DIR="${UPD_SHARED_DATA_DIR}" UPD_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
  upd_set_warnings(${T_NAME})
  include(GoogleTest)
  gtest_discover_tests(${T_NAME} DISCOVERY_TIMEOUT 60
                       PROPERTIES ENVIRONMENT "UPD_SHARED_DATA_DIR=${UPD_SHARED_DATA_DIR}")
endfunction()

# upd_install_library(upd_<name>): the library is exported as upd::<name> from its own export
# set (upd_<name>-targets.cmake, loaded by upd_navConfig.cmake in dependency order), with its
# public headers (<dir>/include/upd/...) under include/. Shared builds get a version and an
# SONAME (pre-1.0: the ABI may change with every minor version) and find their sibling
# libraries beside themselves once installed.
function(upd_install_library target)
  string(REGEX REPLACE "^upd_" "" name ${target})
  get_target_property(src_dir ${target} SOURCE_DIR)
  target_include_directories(${target} PUBLIC $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  set_target_properties(${target} PROPERTIES
    EXPORT_NAME ${name}
    VERSION ${PROJECT_VERSION}
    SOVERSION ${PROJECT_VERSION_MAJOR}.${PROJECT_VERSION_MINOR}
    INSTALL_RPATH "$ORIGIN")
  install(TARGETS ${target} EXPORT ${target}-targets
    LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
    ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
    RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
  install(DIRECTORY ${src_dir}/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
  install(EXPORT ${target}-targets NAMESPACE upd::
    DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/upd_nav)
  set_property(GLOBAL APPEND PROPERTY UPD_INSTALLED_LIBRARIES ${name})
endfunction()
