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
               ${CMAKE_SOURCE_DIR}/tests/unit/test_subset_adaptive.cpp
               ${CMAKE_SOURCE_DIR}/tests/numeric/test_subset_estimates.cpp ${CMAKE_SOURCE_DIR}/tests/unit/test_stopping.cpp
               ${CMAKE_SOURCE_DIR}/tests/unit/test_allowable.cpp ${CMAKE_SOURCE_DIR}/tests/unit/test_monotone_fit.cpp
               ${CMAKE_SOURCE_DIR}/tests/unit/test_importance_sampling.cpp)
target_link_libraries(truss_tests_rare PRIVATE truss_sampling catch_main)
target_include_directories(truss_tests_rare PRIVATE ${CMAKE_SOURCE_DIR}/tests)
add_test(NAME rare_failures COMMAND truss_tests_rare)
# The analytic cases from the command line, for the OpenTURNS cross-check.
add_executable(truss_subset_analytic ${CMAKE_SOURCE_DIR}/tests/numeric/subset_analytic.cpp)
target_link_libraries(truss_subset_analytic PRIVATE truss_sampling CLI11::CLI11)
target_include_directories(truss_subset_analytic PRIVATE ${CMAKE_SOURCE_DIR}/tests)
# Cross-entropy importance sampling on swept analytic cases, for bench/importance_coverage.py.
add_executable(truss_importance_analytic ${CMAKE_SOURCE_DIR}/tests/numeric/importance_analytic.cpp)
target_link_libraries(truss_importance_analytic PRIVATE truss_sampling CLI11::CLI11)
target_include_directories(truss_importance_analytic PRIVATE ${CMAKE_SOURCE_DIR}/tests)
# The same linear limit state through OpenTURNS' SubsetSampling: the 95 % intervals overlap (about 1 s).
add_test(NAME subset_openturns COMMAND /usr/bin/python3 ${CMAKE_SOURCE_DIR}/tests/numeric/test_subset_openturns.py
         --tool $<TARGET_FILE:truss_subset_analytic>)

# The optional x86-64-v4 clones (TRUSS_SIMD_CLONES, src/sampling/simd_clones.hpp) against the
# portable build of the same sources: one program linked with each writes the uniforms and
# quantiles of its plans; the two outputs must be equal byte for byte.
if(TRUSS_SIMD_CLONES)
  list(TRANSFORM TRUSS_SAMPLING_SOURCES PREPEND ${CMAKE_SOURCE_DIR}/ OUTPUT_VARIABLE portable_sources)
  add_library(truss_sampling_portable STATIC ${portable_sources})
  target_include_directories(truss_sampling_portable PUBLIC ${CMAKE_SOURCE_DIR}/src)
  target_include_directories(truss_sampling_portable SYSTEM PRIVATE ${Boost_INCLUDE_DIRS})
  target_link_libraries(truss_sampling_portable PUBLIC fmt::fmt)
  target_compile_features(truss_sampling_portable PUBLIC cxx_std_20)
  if(CMAKE_CXX_COMPILER_ID MATCHES "GNU|Clang")
    target_compile_options(truss_sampling_portable PRIVATE -ffp-contract=off)
  endif()
  add_executable(sampling_simd_bits ${CMAKE_SOURCE_DIR}/tests/unit/sampling_simd_bits.cpp)
  target_link_libraries(sampling_simd_bits PRIVATE truss_sampling)
  add_executable(sampling_portable_bits ${CMAKE_SOURCE_DIR}/tests/unit/sampling_simd_bits.cpp)
  target_link_libraries(sampling_portable_bits PRIVATE truss_sampling_portable)
  add_test(NAME sampling_simd_bits
           COMMAND sh -c "\"$1\" > sampling_simd.bin && \"$2\" > sampling_portable.bin && cmp sampling_simd.bin sampling_portable.bin && test -s sampling_simd.bin"
                   sh $<TARGET_FILE:sampling_simd_bits> $<TARGET_FILE:sampling_portable_bits>
           WORKING_DIRECTORY ${CMAKE_CURRENT_BINARY_DIR})
  set_tests_properties(sampling_simd_bits PROPERTIES LABELS quick)
endif()
