// SPDX-License-Identifier: BSD-3-Clause
#include "afam/base/thread_priority.hpp"

#include <algorithm>
#include <cerrno>

#if defined(__linux__)
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>
#endif

namespace afam {

#if defined(__linux__)

namespace {

id_t thisThreadId() { return id_t(::syscall(SYS_gettid)); }

}  // namespace

int thisThreadNice() {
  errno = 0;
  const int nice = ::getpriority(PRIO_PROCESS, thisThreadId());
  return errno == 0 ? nice : 0;
}

bool lowerThisThreadPriority(int increment) {
  if (increment <= 0) return true;
  const int target = std::min(19, thisThreadNice() + increment);
  return ::setpriority(PRIO_PROCESS, thisThreadId(), target) == 0;
}

#else

int thisThreadNice() { return 0; }

bool lowerThisThreadPriority(int increment) { return increment <= 0; }

#endif

}  // namespace afam
