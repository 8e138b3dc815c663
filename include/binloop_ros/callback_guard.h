#pragma once
// The one place where the nodelets' callbacks, timers and service handlers meet exceptions. nodelet's worker
// threads do not catch: one exception leaving a callback ends the manager process and every stage in it. So
// each callback a nodelet registers goes through a CallbackGuard, which catches whatever it throws, logs it
// (throttled), counts it and keeps the last one for the stage's diagnostics; the message is dropped and the
// stage goes on.
#include <ros/console.h>
#include <ros/node_handle.h>

#include <atomic>
#include <exception>
#include <mutex>
#include <string>
#include <utility>

namespace binloop_ros {

class CallbackGuard {
 public:
  explicit CallbackGuard(std::string stage) : stage_(std::move(stage)) {}
  CallbackGuard(const CallbackGuard&) = delete;
  CallbackGuard& operator=(const CallbackGuard&) = delete;

  /// Runs `f`; an exception it throws is reported as "<what>: <message>" and swallowed. Returns whether `f`
  /// finished without one.
  template <class F>
  bool run(const std::string& what, F&& f) noexcept {
    try {
      f();
      return true;
    } catch (const std::exception& e) {
      report(what, e.what());
    } catch (...) {
      report(what, "an exception that is not a std::exception");
    }
    return false;
  }

  /// A callback for NodeHandle::subscribe, a message_filters synchronizer or a timer: `f` with any
  /// arguments, run through run().
  template <class F>
  auto wrap(std::string what, F f) {
    return [this, what = std::move(what), f = std::move(f)](const auto&... args) {
      run(what, [&] { f(args...); });
    };
  }

  /// Subscribes `method` of `obj` to `topic` through the guard.
  template <class Msg, class Obj>
  ros::Subscriber subscribe(ros::NodeHandle& nh, const std::string& topic, uint32_t queue,
                            void (Obj::*method)(const boost::shared_ptr<const Msg>&), Obj* obj) {
    return nh.subscribe<Msg>(topic, queue,
                             wrap(topic + " callback", [obj, method](const boost::shared_ptr<const Msg>& m) {
                               (obj->*method)(m);
                             }));
  }

  uint64_t failures() const { return failures_; }
  std::string lastFailure() const {
    std::lock_guard<std::mutex> lk(m_);
    return last_;
  }

 private:
  void report(const std::string& what, const std::string& message) noexcept {
    try {
      ++failures_;
      {
        std::lock_guard<std::mutex> lk(m_);
        last_ = what + ": " + message;
      }
      ROS_ERROR_THROTTLE(1.0, "binloop/%s: %s: %s (dropped; the stage goes on)", stage_.c_str(), what.c_str(),
                         message.c_str());
    } catch (...) {  // out of memory for the message: the count is what is left
    }
  }

  std::string stage_;
  std::atomic<uint64_t> failures_{0};
  mutable std::mutex m_;
  std::string last_;
};

}  // namespace binloop_ros
