// Work a run prepares ahead of need (the rollover quantities' quadrature
// rule, the PDF draws) on a thread of its own, while the filter estimates.
// On a machine of two cores both are busy at once, and the estimating thread
// lost a tenth of its time to them at start-up; marked as background work
// (nice + 10: on Linux a thread's own, and the threads it starts inherit
// it), such a thread takes the cores the estimation leaves. Nothing where
// the call is not available.
#pragma once

#if defined(__linux__)
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>
#endif

namespace pc_ekf {

inline void markBackgroundThread() {
#if defined(__linux__)
  const auto tid = static_cast<id_t>(::syscall(SYS_gettid));
  const int now = ::getpriority(PRIO_PROCESS, tid);
  ::setpriority(PRIO_PROCESS, tid, now + 10);  // raising it needs no privilege; failure leaves it
#endif
}

}  // namespace pc_ekf
