// The allocator's settings for a run that makes and frees many short-lived
// buffers (glibc malloc). By default glibc returns the top of its heap to
// the system once 128 KB are free there and serves every block above its
// mmap threshold with a fresh mapping, so each new batch of buffers touches
// fresh pages again: page faults were a tenth of a road-free run's time.
// Kept instead (at most 64 MB free at the top, blocks below 32 MB from the
// heap), the pages are touched once; the peak memory is what it was.
#pragma once

#include <malloc.h>

namespace pc_ekf {

inline void keepFreedHeap() {
  mallopt(M_TRIM_THRESHOLD, 64 << 20);
  mallopt(M_TOP_PAD, 4 << 20);
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
}

}  // namespace pc_ekf
