# Unity builds (-DCMAKE_UNITY_BUILD=ON; scripts/sanitize.sh uses one: the sanitized build compiles
# each heavy header once per batch instead of once per file). These files define names of their
# own in an anonymous namespace (kNaN, kTraits, check_flag, test helpers) that another file of
# their target defines too, so they are compiled alone, in both directories that list sources.
set(TRUSS_UNITY_ALONE
    src/integrators/dop853.cpp src/integrators/ida_integrator.cpp src/io/suggest.cpp
    src/sampling/importance_sampling.cpp src/sampling/monotone_fit.cpp src/sampling/reweighting.cpp
    src/sampling/sobol_indices.cpp src/sampling/subset_simulation.cpp src/statistics/column_stats.cpp
    tests/numeric/test_robustness.cpp tests/unit/test_dop853.cpp tests/unit/test_json_h5.cpp
    tests/unit/test_importance_method.cpp tests/unit/test_methods.cpp tests/unit/test_stop_method.cpp
    tests/unit/test_subset_method.cpp
    tests/unit/test_toy_sweep.cpp)
list(TRANSFORM TRUSS_UNITY_ALONE PREPEND ${CMAKE_SOURCE_DIR}/)
set_source_files_properties(${TRUSS_UNITY_ALONE} DIRECTORY ${CMAKE_SOURCE_DIR} ${CMAKE_SOURCE_DIR}/tests
                            PROPERTIES SKIP_UNITY_BUILD_INCLUSION ON)
