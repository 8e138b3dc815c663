#pragma once
// CPU time a nodelet spends in its callbacks. Nodelets in one manager share its worker threads, so the
// process's CPU cannot be split by nodelet; each callback instead adds the CPU time of its own thread
// (CLOCK_THREAD_CPUTIME_ID) while it runs. Reported in each nodelet's diagnostics.
#include <time.h>

#include <atomic>

namespace binloop_ros {

class CpuMeter {
 public:
  /// Adds the calling thread's CPU time from construction to destruction to `meter`.
  class Scope {
   public:
    explicit Scope(CpuMeter& m) : m_(m), t0_(now()) {}
    ~Scope() { m_.ns_ += now() - t0_; }
    Scope(const Scope&) = delete;
    Scope& operator=(const Scope&) = delete;

   private:
    CpuMeter& m_;
    long long t0_;
  };

  double seconds() const { return static_cast<double>(ns_.load()) * 1e-9; }

 private:
  static long long now() {
    timespec ts{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return static_cast<long long>(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
  }
  std::atomic<long long> ns_{0};
};

}  // namespace binloop_ros
