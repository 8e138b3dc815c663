#!/usr/bin/python3
"""Watches a running binloop graph for the soak benchmark (scripts/bench_soak.sh) and writes what it saw.

For --minutes it records every tracked frame (state, tracking's own times, the delay from the images' stamp
to the pose's arrival on the bag's clock), notices each time the bag wraps round (the stamp goes back), and
every --sample-s seconds the manager's resident memory, the graph's keyframe count (/binloop/statistics)
and the largest message each /binloop topic carried since the last sample. Prints a table and writes
soak.json into --out.
"""
import argparse
import json
import os
import statistics
import sys
import threading
import time

import rospy
from binloop.msg import TrackedFrame
from binloop.srv import Statistics

LOST, NOT_INITIALIZED = 2, 0


def rss_mb(pids):
    """The processes' resident memory together; None once one of them is gone (a respawn is a new process)."""
    total = 0.0
    for pid in pids:
        try:
            with open(f"/proc/{pid}/status") as f:
                rss = [int(line.split()[1]) for line in f if line.startswith("VmRSS:")]
        except OSError:
            return None
        if not rss:
            return None
        total += rss[0] / 1024.0
    return total


def p95(values):
    if not values:
        return float("nan")
    v = sorted(values)
    return v[min(len(v) - 1, int(0.95 * len(v)))]


class Monitor:
    def __init__(self, pid, sample_s):
        self.pid, self.sample_s = pid, sample_s
        self.lock = threading.Lock()
        self.frames = []  # (wall_s, stamp_s, state, work_ms, delay_ms)
        self.wraps = []   # wall time of each wrap and frames until the first tracked one after it
        self.last_stamp = None
        self.sizes = {}   # topic -> largest message since the last sample
        self.samples = []
        self.subs = []
        self.start = time.time()

    def on_frame(self, m):
        now = rospy.get_rostime().to_sec()
        stamp = m.header.stamp.to_sec()
        with self.lock:
            if self.last_stamp is not None and stamp < self.last_stamp - 1.0:
                self.wraps.append({"wall_s": time.time() - self.start, "frames_to_track": None})
            self.last_stamp = stamp
            tracked = m.state not in (LOST, NOT_INITIALIZED)
            for w in self.wraps:
                if w["frames_to_track"] is None:
                    w.setdefault("_n", 0)
                    w["_n"] += 1
                    if tracked:
                        w["frames_to_track"] = w.pop("_n")
            self.frames.append((time.time() - self.start, stamp, m.state, m.extract_ms + m.stereo_ms + m.track_ms,
                                (now - stamp) * 1000.0))

    def on_any(self, topic):
        def cb(msg):
            with self.lock:
                self.sizes[topic] = max(self.sizes.get(topic, 0), len(msg._buff))
        return cb

    def subscribe_outputs(self):
        seen = {s.name for s in self.subs}
        for topic, _ in rospy.get_published_topics("/binloop"):
            # tracked_frame has its typed subscriber already (rospy keeps one type a topic)
            if topic not in seen and topic != "/binloop/tracked_frame":
                self.subs.append(rospy.Subscriber(topic, rospy.AnyMsg, self.on_any(topic), queue_size=5))

    def sample(self):
        keyframes = None
        try:
            values = rospy.ServiceProxy("/binloop/statistics", Statistics)().values
            keyframes = next((int(v.value) for v in values if v.key == "local_mapping/keyframes"), None)
        except Exception:  # the graph may be busy; the sample goes without it
            pass
        with self.lock:
            sizes, self.sizes = self.sizes, {}
        self.samples.append({"wall_s": time.time() - self.start, "rss_mb": rss_mb(self.pid), "keyframes": keyframes,
                             "max_bytes": sizes})


def window(frames, lo, hi, idx):
    return [f[idx] for f in frames if lo <= f[0] < hi]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--minutes", type=float, default=60)
    ap.add_argument("--pid", type=int, action="append", required=True,
                    help="the graph's process (the nodelet manager, or each stage of the split launch)")
    ap.add_argument("--sample-s", type=float, default=30)
    ap.add_argument("--window-min", type=float, default=10, help="the first and last stretch compared")
    ap.add_argument("--out", required=True)
    a = ap.parse_args(rospy.myargv()[1:])
    rospy.init_node("soak_monitor", anonymous=True)
    mon = Monitor(a.pid, a.sample_s)
    rospy.Subscriber("/binloop/tracked_frame", TrackedFrame, mon.on_frame, queue_size=100)
    end = mon.start + a.minutes * 60
    next_sample = mon.start + 5
    while not rospy.is_shutdown() and time.time() < end:
        if time.time() >= next_sample:
            mon.subscribe_outputs()
            mon.sample()
            next_sample += a.sample_s
        time.sleep(0.2)
    mon.subscribe_outputs()
    mon.sample()

    total = time.time() - mon.start
    w = min(a.window_min * 60, total / 3)
    with mon.lock:
        frames = list(mon.frames)
        wraps = [dict(x) for x in mon.wraps]
    first_work, last_work = window(frames, 0, w, 3), window(frames, total - w, total + 1, 3)
    first_delay, last_delay = window(frames, 0, w, 4), window(frames, total - w, total + 1, 4)
    tracked = sum(1 for f in frames if f[2] not in (LOST, NOT_INITIALIZED))
    kf = [s for s in mon.samples if s["keyframes"] and s["rss_mb"]]
    topics = sorted({t for s in mon.samples for t in s["max_bytes"]})
    growth = {}
    for t in topics:
        early = [s["max_bytes"][t] for s in mon.samples if t in s["max_bytes"] and s["wall_s"] < w]
        late = [s["max_bytes"][t] for s in mon.samples if t in s["max_bytes"] and s["wall_s"] >= total - w]
        if early and late:
            growth[t] = {"first_max_bytes": max(early), "last_max_bytes": max(late)}
    mb_per_kf = None
    if len(kf) >= 2 and kf[-1]["keyframes"] > kf[0]["keyframes"]:
        mb_per_kf = (kf[-1]["rss_mb"] - kf[0]["rss_mb"]) / (kf[-1]["keyframes"] - kf[0]["keyframes"])
    result = {
        "minutes": total / 60, "frames": len(frames), "frames_tracked": tracked, "wraps": len(wraps),
        "wraps_tracked_again": sum(1 for x in wraps if x["frames_to_track"] is not None),
        "frames_to_track_after_wrap_max": max((x["frames_to_track"] or 0 for x in wraps), default=0),
        "window_min": w / 60,
        "work_ms_p95_first": p95(first_work), "work_ms_p95_last": p95(last_work),
        "delay_ms_p95_first": p95(first_delay), "delay_ms_p95_last": p95(last_delay),
        "rss_mb_first": kf[0]["rss_mb"] if kf else None, "rss_mb_last": kf[-1]["rss_mb"] if kf else None,
        "keyframes_first": kf[0]["keyframes"] if kf else None, "keyframes_last": kf[-1]["keyframes"] if kf else None,
        "samples_with_a_process_gone": sum(1 for s in mon.samples if s["rss_mb"] is None),
        "mb_per_keyframe": mb_per_kf, "message_bytes": growth, "samples": mon.samples, "wrap_list": wraps,
    }
    os.makedirs(a.out, exist_ok=True)
    with open(os.path.join(a.out, "soak.json"), "w") as f:
        json.dump(result, f, indent=1)

    def fmt(x, d=1):
        return "-" if x is None else f"{x:.{d}f}"
    print(f"soak: {result['minutes']:.1f} min, {len(frames)} frames ({tracked} tracked), {len(wraps)} wraps, "
          f"{result['wraps_tracked_again']} tracked again (at most {result['frames_to_track_after_wrap_max']} frames after a wrap)")
    print("| | first {0:g} min | last {0:g} min | last / first |".format(round(w / 60, 1)))
    print("|---|---|---|---|")
    for name, f0, f1 in (("tracking work p95 (ms)", result["work_ms_p95_first"], result["work_ms_p95_last"]),
                         ("stamp-to-pose delay p95 (ms)", result["delay_ms_p95_first"], result["delay_ms_p95_last"])):
        print(f"| {name} | {fmt(f0)} | {fmt(f1)} | {fmt(f1 / f0 if f0 else None, 2)} |")
    print(f"| the graph's resident memory (MB) | {fmt(result['rss_mb_first'])} | {fmt(result['rss_mb_last'])} | |")
    print(f"| keyframes | {result['keyframes_first']} | {result['keyframes_last']} | |")
    if result["samples_with_a_process_gone"]:
        print(f"a process of the graph was gone (died or respawned) in {result['samples_with_a_process_gone']} "
              f"of {len(mon.samples)} samples")
    print(f"MB per keyframe (resident growth / keyframes added): {fmt(mb_per_kf, 3)}")
    for t, g in growth.items():
        print(f"  {t}: largest message {g['first_max_bytes']} B in the first window, {g['last_max_bytes']} B in the last")
    return 0


if __name__ == "__main__":
    sys.exit(main())
