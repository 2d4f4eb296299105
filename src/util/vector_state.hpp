// Clearing the upper halves of the vector registers after a library's vector kernel.
//
// Contract: clear_upper_vector_state() leaves every register value the caller can hold across a
// call unchanged (the x86-64 ABI saves no vector register across calls, and VZEROUPPER keeps the
// low 128 bits), and only clears the state the CPU tracks for the upper halves of the YMM/ZMM
// registers. Why: ISA-L's AVX2/AVX-512 kernels (CRC-32, DEFLATE, Adler-32) return with that state
// dirty; the scalar SSE2 code compiled for the model then pays for that state on every
// instruction until it is cleared (the cost: docs/benchmarks.md, "The vector state after ISA-L's
// kernels"). Call it after every ISA-L call. A no-op on CPUs without AVX and outside x86-64.
#pragma once

namespace truss::util {

void clear_upper_vector_state();

}  // namespace truss::util
