#include "binloop/util/thread_priority.h"

#if defined(__linux__)
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>
#endif

namespace binloop {

#if defined(__linux__)
namespace {
// On Linux a nice value belongs to a thread (its kernel task id), not to the whole process.
id_t thisThreadId() { return static_cast<id_t>(syscall(SYS_gettid)); }
}  // namespace

int thisThreadNice() { return getpriority(PRIO_PROCESS, thisThreadId()); }

bool lowerThisThreadPriority(int nice) {
  return setpriority(PRIO_PROCESS, thisThreadId(), thisThreadNice() + nice) == 0;
}
#else
int thisThreadNice() { return 0; }

bool lowerThisThreadPriority(int) { return false; }
#endif

}  // namespace binloop
