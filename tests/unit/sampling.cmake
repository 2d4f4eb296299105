# sampling.cmake — tests of the campaign sampling library (the library target truss_sampling is
# defined in the top-level CMakeLists.txt). Included from tests/CMakeLists.txt.

find_package(Threads REQUIRED)  # the determinism test shares one plan between threads
add_executable(truss_tests_sampling ${CMAKE_SOURCE_DIR}/tests/unit/test_sampling.cpp
                                     ${CMAKE_SOURCE_DIR}/tests/unit/test_saltelli_design.cpp)
target_link_libraries(truss_tests_sampling PRIVATE truss_sampling catch_main Threads::Threads)
add_test(NAME truss_tests_sampling COMMAND truss_tests_sampling)

# Rare failures and sequential stopping (src/sampling/): subset simulation on analytic limit states
# against their exact probabilities, its byte formats and resume, and the stopping rules against
# scipy's binomial and beta laws. About 3 s.
add_executable(truss_tests_rare ${CMAKE_SOURCE_DIR}/tests/unit/test_subset_simulation.cpp
               ${CMAKE_SOURCE_DIR}/tests/numeric/test_subset_estimates.cpp ${CMAKE_SOURCE_DIR}/tests/unit/test_stopping.cpp
               ${CMAKE_SOURCE_DIR}/tests/unit/test_allowable.cpp)
target_link_libraries(truss_tests_rare PRIVATE truss_sampling catch_main)
target_include_directories(truss_tests_rare PRIVATE ${CMAKE_SOURCE_DIR}/tests)
add_test(NAME rare_failures COMMAND truss_tests_rare)
# The analytic cases from the command line, for the OpenTURNS cross-check.
add_executable(truss_subset_analytic ${CMAKE_SOURCE_DIR}/tests/numeric/subset_analytic.cpp)
target_link_libraries(truss_subset_analytic PRIVATE truss_sampling CLI11::CLI11)
target_include_directories(truss_subset_analytic PRIVATE ${CMAKE_SOURCE_DIR}/tests)
# The same linear limit state through OpenTURNS' SubsetSampling: the 95 % intervals overlap (about 1 s).
add_test(NAME subset_openturns COMMAND /usr/bin/python3 ${CMAKE_SOURCE_DIR}/tests/numeric/test_subset_openturns.py
         --tool $<TARGET_FILE:truss_subset_analytic>)
