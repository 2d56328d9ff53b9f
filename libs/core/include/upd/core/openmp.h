// The OpenMP team as the frame stages use it, without an #ifdef at every use: the number of
// threads of the current team, this thread's place in it, and the most a region would get. One
// thread when the including file is built without OpenMP.
//
// The functions are static (internal linkage): a file built with OpenMP and one built without
// each get their own definition.
#pragma once

#ifdef _OPENMP
#include <omp.h>
#endif

namespace upd::core::openmp {

/// Threads of the current team (1 outside a parallel region).
static inline int teamSize() {
#ifdef _OPENMP
  return omp_get_num_threads();
#else
  return 1;
#endif
}

/// This thread's index in the current team, 0 to teamSize() - 1.
static inline int threadIndex() {
#ifdef _OPENMP
  return omp_get_thread_num();
#else
  return 0;
#endif
}

/// The team size a parallel region started here would get.
static inline int maxThreads() {
#ifdef _OPENMP
  return omp_get_max_threads();
#else
  return 1;
#endif
}

}  // namespace upd::core::openmp
