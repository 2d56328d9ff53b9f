# Shared build helpers: warnings on every project target, one helper to add a test.
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
