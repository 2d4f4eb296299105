// simd_clones.hpp — TRUSS_SAMPLING_CLONES, for the per-run loops of the sampling library (private to
// src/sampling/: the Latin hypercube's permutations and strata, the normal quantile in bulk). The
// one file of src/ with machine-specific code (tests/style/check_layers.py), and optional: the
// CMake option TRUSS_SIMD_CLONES (on by default) defines TRUSS_SIMD_CLONES=1.
//
// A function marked with it is compiled twice, for x86-64-v4 (AVX-512: eight 64-bit integer
// multiplications or double divisions per instruction) and for the baseline, and the loader picks
// the one the CPU runs. Only loops whose every operation is exact or correctly rounded (integer
// arithmetic, exact conversions, IEEE +, *, / with no contraction: the library is compiled with
// -ffp-contract=off) are marked, so both versions give the same bits; the portable build (option
// off) is the reference, and ctest sampling_simd_bits compares the two builds' uniforms and
// quantiles byte for byte. Elsewhere, or with the option off: the portable loops alone.
#pragma once

#if defined(TRUSS_SIMD_CLONES) && TRUSS_SIMD_CLONES && defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define TRUSS_SAMPLING_CLONES __attribute__((target_clones("arch=x86-64-v4", "default")))
#else
#define TRUSS_SAMPLING_CLONES
#endif
