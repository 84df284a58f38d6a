#pragma once

// x86 multiversioning, defined once for every library that uses it (the core's kernels, the slip
// detector's scoring, the extraction benchmark's floor). The build has no -mavx2: code for newer
// processors is compiled by function attribute only and chosen at run time.
//
// TACTILE_AVX2 (and TACTILE_AVX2_INLINE for its helpers, inlined into it): a function compiled
// for AVX2 and FMA, defined only where the compiler can (x86-64, GCC or Clang). Call it only when
// cpu_has_avx2_fma() says the processor has both.
//
// TACTILE_CLONES: a function compiled twice, for x86-64-v3 (AVX2, FMA) and the baseline; the
// dynamic loader picks the clone once (ifunc). Empty elsewhere and in builds that define
// TACTILE_NO_MULTIVERSION (the baseline only). The compiler contracts a * b + c into one FMA in
// the x86-64-v3 clone (one rounding instead of two): its sums may differ in the last bit.
//
// TACTILE_CLONES_SAME_BITS: the same, for AVX2 without FMA: every operation rounds as in the
// baseline, so the results are the same bits on every processor (the rig's renderer: a scenario's
// images and report do not depend on the machine that ran it).
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define TACTILE_AVX2 __attribute__((target("avx2,fma")))
#define TACTILE_AVX2_INLINE __attribute__((target("avx2,fma"), always_inline)) inline

namespace tactile::detail {

// Whether this processor runs TACTILE_AVX2 code. Safe in static initializers.
inline bool cpu_has_avx2_fma() noexcept {
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
}

}  // namespace tactile::detail
#endif

#if defined(TACTILE_AVX2) && !defined(TACTILE_NO_MULTIVERSION)
#define TACTILE_CLONES __attribute__((target_clones("arch=x86-64-v3", "default")))
#define TACTILE_CLONES_SAME_BITS __attribute__((target_clones("avx2", "default")))
#else
#define TACTILE_CLONES
#define TACTILE_CLONES_SAME_BITS
#endif
