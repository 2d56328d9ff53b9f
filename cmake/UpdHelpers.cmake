# Shared build helpers: warnings on every project target, one helper to add a library, one to
# add a test, one to install a library with its headers into the exported CMake package
# (upd_nav, namespace upd::).
include(GNUInstallDirs)

function(upd_set_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wno-deprecated-copy
                                           $<$<CXX_COMPILER_ID:GNU>:-Wshadow=local>)
endfunction()

# upd_add_library(name): the library upd_<name> (alias upd::<name>) of the sources in
# <dir>/src/*.cpp, its public headers in <dir>/include, C++17, position-independent code (a
# static build's libraries can go into shared objects), with the project's warnings. The caller
# adds its links and upd_install_library().
function(upd_add_library name)
  file(GLOB sources CONFIGURE_DEPENDS ${CMAKE_CURRENT_SOURCE_DIR}/src/*.cpp)
  add_library(upd_${name} ${sources})
  add_library(upd::${name} ALIAS upd_${name})
  target_include_directories(upd_${name} PUBLIC $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>)
  target_compile_features(upd_${name} PUBLIC cxx_std_17)
  set_target_properties(upd_${name} PROPERTIES POSITION_INDEPENDENT_CODE ON)
  upd_set_warnings(upd_${name})
endfunction()

# upd_add_module(name OF upd_<library> DEFINE VAR SOURCES a.cpp ... [LINKS ...]
# [DEFINITIONS ...]): a part of the library loaded only when used (upd/mrpt_bridge/module.h),
# for the heavy libraries it LINKS. In a shared build a MODULE beside the library (the build
# tree and the installed lib/), whose file name the library gets as the string VAR; in a static
# build the SOURCES are the library's own and VAR is not defined. DEFINITIONS are the SOURCES'
# private compile definitions. The modules are listed in the global property UPD_MODULES (the
# tool depends on them).
function(upd_add_module name)
  cmake_parse_arguments(M "" "OF;DEFINE" "SOURCES;LINKS;DEFINITIONS" ${ARGN})
  if(BUILD_SHARED_LIBS)
    add_library(${name} MODULE ${M_SOURCES})
    target_link_libraries(${name} PRIVATE ${M_OF} ${M_LINKS})
    target_compile_definitions(${name} PRIVATE ${M_DEFINITIONS})
    set_target_properties(${name} PROPERTIES INSTALL_RPATH "$ORIGIN")
    upd_set_warnings(${name})
    target_compile_definitions(${M_OF} PRIVATE ${M_DEFINE}="$<TARGET_FILE_NAME:${name}>")
    install(TARGETS ${name} LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
    set_property(GLOBAL APPEND PROPERTY UPD_MODULES ${name})  # (built with the tool)
  else()
    target_sources(${M_OF} PRIVATE ${M_SOURCES})
    target_link_libraries(${M_OF} PRIVATE ${M_LINKS})
    target_compile_definitions(${M_OF} PRIVATE ${M_DEFINITIONS})
  endif()
endfunction()

# upd_add_test(NAME name SOURCES a.cpp b.cpp LIBS lib1 lib2 [LABEL label]): LABEL is the ctest
# label of its test cases, the library it tests (`ctest -L '^maps$'`; scripts/sanitize.sh's scopes).
function(upd_add_test)
  cmake_parse_arguments(T "" "NAME;LABEL" "SOURCES;LIBS" ${ARGN})
  add_executable(${T_NAME} ${T_SOURCES})
  target_link_libraries(${T_NAME} PRIVATE ${T_LIBS} GTest::gtest GTest::gtest_main)
  target_compile_definitions(${T_NAME} PRIVATE
    UPD_SHARED_DATA_DIR="${UPD_SHARED_DATA_DIR}" UPD_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
  upd_set_warnings(${T_NAME})
  include(GoogleTest)
  gtest_discover_tests(${T_NAME} DISCOVERY_TIMEOUT 60
                       PROPERTIES ENVIRONMENT "UPD_SHARED_DATA_DIR=${UPD_SHARED_DATA_DIR}"
                                  LABELS "${T_LABEL}")
endfunction()

# upd_install_library(upd_<name> [PACKAGES spec...] [STATIC_PACKAGES spec...]): the library is
# exported as upd::<name> from its own export set (upd_<name>-targets.cmake), with its public
# headers (<dir>/include/upd/...) under include/. PACKAGES are the find_package arguments of
# what its exported interface names (e.g. "MRPT 2.5 COMPONENTS obs"): upd_navConfig.cmake finds
# them before loading the targets; STATIC_PACKAGES are those it links privately, needed by
# consumers of a static build only. Shared builds get a version and an SONAME (pre-1.0: the ABI
# may change with every minor version), find their sibling libraries beside themselves once
# installed, and call their own functions directly.
function(upd_install_library target)
  cmake_parse_arguments(L "" "" "PACKAGES;STATIC_PACKAGES" ${ARGN})
  string(REGEX REPLACE "^upd_" "" name ${target})
  get_target_property(src_dir ${target} SOURCE_DIR)
  target_include_directories(${target} PUBLIC $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  set_target_properties(${target} PROPERTIES
    EXPORT_NAME ${name}
    VERSION ${PROJECT_VERSION}
    SOVERSION ${PROJECT_VERSION_MAJOR}.${PROJECT_VERSION_MINOR}
    INSTALL_RPATH "$ORIGIN")
  if(BUILD_SHARED_LIBS AND CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
    # A call inside the library is not interposed by another definition at run time: GCC may
    # inline it and call it directly, as in a static build (clang's default).
    target_compile_options(${target} PRIVATE -fno-semantic-interposition)
  endif()
  install(TARGETS ${target} EXPORT ${target}-targets
    LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
    ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
    RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
  install(DIRECTORY ${src_dir}/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
  install(EXPORT ${target}-targets NAMESPACE upd::
    DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/upd_nav)
  set_property(GLOBAL APPEND PROPERTY UPD_INSTALLED_LIBRARIES ${name})
  set_property(GLOBAL PROPERTY UPD_PACKAGES_${name} "${L_PACKAGES}")
  set_property(GLOBAL PROPERTY UPD_STATIC_PACKAGES_${name} "${L_STATIC_PACKAGES}")
endfunction()

# The parts of upd_navConfig.cmake that differ per library: into needs_var, for each installed
# library in the order they were added (each after those it links), the upd libraries it links;
# into find_var, the packages to find before loading its targets.
function(upd_package_config_code needs_var find_var)
  get_property(names GLOBAL PROPERTY UPD_INSTALLED_LIBRARIES)
  set(needs_code "set(_upd_installed ${names})\n")
  set(find_code "")
  foreach(name IN LISTS names)
    get_target_property(links upd_${name} LINK_LIBRARIES)
    set(needs "")
    foreach(l IN LISTS links)
      if(l MATCHES "^upd(::|_)([a-z0-9_]+)$" AND CMAKE_MATCH_2 IN_LIST names)
        list(APPEND needs ${CMAKE_MATCH_2})
      endif()
    endforeach()
    string(APPEND needs_code "set(_upd_needs_${name} ${needs})\n")
    string(APPEND find_code "    if(_c STREQUAL \"${name}\")\n")
    get_property(packages GLOBAL PROPERTY UPD_PACKAGES_${name})
    foreach(p IN LISTS packages)
      string(APPEND find_code "      find_dependency(${p})\n")
    endforeach()
    get_property(packages GLOBAL PROPERTY UPD_STATIC_PACKAGES_${name})
    foreach(p IN LISTS packages)
      string(APPEND find_code "      if(NOT _upd_shared)\n        find_dependency(${p})\n      endif()\n")
    endforeach()
    string(APPEND find_code "    endif()\n")
  endforeach()
  set(${needs_var} "${needs_code}" PARENT_SCOPE)
  set(${find_var} "${find_code}" PARENT_SCOPE)
endfunction()
