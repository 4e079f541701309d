// Process-wide allocator setting for the LibTorch commands (train, bench train-step).
#pragma once

#ifdef __GLIBC__
#include <malloc.h>
#endif

namespace occtrack::app {

/// A CPU training step allocates and frees tensors of tens of megabytes (one PointNet layer's activations at
/// batch 256 are 51,200 points x 256 floats, 52 MB). glibc serves blocks above its mmap threshold with mmap
/// and gives them back with munmap, so every step page-faults its whole working set in again: about 40% of
/// the networks' time on one core (bench train-step, batch 256: 550 ms -> 315 ms without it). Keeping large
/// blocks in the heap, and the heap untrimmed, holds the peak footprint instead. Called once, before the
/// first tensor; a no-op outside glibc.
inline void keep_large_allocations() {
#ifdef __GLIBC__
  mallopt(M_MMAP_THRESHOLD, 1 << 30);
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
#endif
}

}  // namespace occtrack::app
