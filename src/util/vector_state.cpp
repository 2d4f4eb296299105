#include "util/vector_state.hpp"

namespace truss::util {

#if defined(__x86_64__)
void clear_upper_vector_state() {
  // VZEROUPPER is an AVX instruction: executed only where the CPU has AVX (looked up once).
  static const bool has_avx = __builtin_cpu_supports("avx");
  if (has_avx) asm volatile("vzeroupper" ::: "memory");
}
#else
void clear_upper_vector_state() {}
#endif

}  // namespace truss::util
