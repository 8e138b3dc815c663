#include "binloop/util/thread_priority.h"

#if defined(__linux__)
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>
#endif

namespace binloop {

bool lowerThisThreadPriority(int nice) {
#if defined(__linux__)
  // On Linux a nice value belongs to a thread (its kernel task id), not to the whole process.
  const auto tid = static_cast<id_t>(syscall(SYS_gettid));
  const int now = getpriority(PRIO_PROCESS, tid);
  return setpriority(PRIO_PROCESS, tid, now + nice) == 0;
#else
  (void)nice;
  return false;
#endif
}

}  // namespace binloop
