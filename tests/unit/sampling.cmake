# sampling.cmake — tests of the campaign sampling library (the library target truss_sampling is
# defined in the top-level CMakeLists.txt). Included from tests/CMakeLists.txt.

find_package(Threads REQUIRED)  # the determinism test shares one plan between threads
add_executable(truss_tests_sampling ${CMAKE_SOURCE_DIR}/tests/unit/test_sampling.cpp
                                     ${CMAKE_SOURCE_DIR}/tests/unit/test_saltelli_design.cpp)
target_link_libraries(truss_tests_sampling PRIVATE truss_sampling catch_main Threads::Threads)
add_test(NAME truss_tests_sampling COMMAND truss_tests_sampling)
