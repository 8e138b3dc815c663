#pragma once
// Background work (the global BA after a loop) yields the CPU to tracking, which must keep the camera's
// pace on a machine with fewer cores than the SLAM has threads.

namespace binloop {

/// The calling thread's own nice value (Linux; 0 elsewhere).
int thisThreadNice();

/// Lowers the calling thread's scheduling priority by `nice` steps (Linux: the thread's own nice value;
/// elsewhere nothing). Returns whether it took effect; failing to lower it is never an error.
bool lowerThisThreadPriority(int nice);

}  // namespace binloop
