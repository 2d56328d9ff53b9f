// UPD_VECTOR_CLONES: what lets the hot loops of the libraries use the machine's vector units.
//
// The libraries are compiled for the baseline x86-64 (SSE2) so that they run anywhere. The few
// loops that dominate a frame are written branch-free over fixed-width lanes and marked
// UPD_VECTOR_CLONES: GCC then compiles them three times (AVX-512, AVX2 + FMA, baseline) and
// picks the version for the running CPU when the program loads. Elsewhere the mark is empty and
// the loops are compiled once, for the baseline.
#pragma once

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__linux__)
#define UPD_VECTOR_CLONES \
  __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define UPD_VECTOR_CLONES
#endif
