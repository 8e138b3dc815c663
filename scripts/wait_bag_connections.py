#!/usr/bin/env python3
"""Waits until a (paused) rosbag player has advertised every topic of its bag and every node subscribed to
one of them is connected to it.

A subscriber registered with the master connects to a new publisher only after the master tells it, over
XML-RPC; under load that takes longer than any fixed delay, and a message published before it is lost.
run-bag starts `rosbag play --pause`, calls this, then unpauses, so the first stereo pair reaches tracking.

usage: wait_bag_connections.py <player node name> <bag> [timeout seconds, default 30]
Exit 0 when connected; 1 (with a message naming what is not connected) at the timeout.
"""
import http.client
import os
import socket
import sys
import time
import xmlrpc.client

import rosbag

CALLER = "/binloop_run_bag"


def master():
    return xmlrpc.client.ServerProxy(os.environ.get("ROS_MASTER_URI", "http://localhost:11311"))


def missing_connections(player, bag_topics):
    """(topic, subscriber) pairs registered with the master but not yet connected to the player; None while
    the player has not advertised all of the bag's topics (it advertises /clock first, then one by one)."""
    code, _, state = master().getSystemState(CALLER)
    if code != 1:
        return None
    publishers, subscribers = state[0], state[1]
    topics = {t for t, nodes in publishers if player in nodes}
    if not bag_topics <= topics:
        return None
    wanted = {(t, n) for t, nodes in subscribers if t in topics for n in nodes if n != player}
    code, _, uri = master().lookupNode(CALLER, player)
    if code != 1:
        return None
    code, _, bus = xmlrpc.client.ServerProxy(uri).getBusInfo(CALLER)
    if code != 1:
        return None
    # getBusInfo rows: [id, destination node, direction, transport, topic, connected (not always sent)]
    connected = {(row[4], row[1]) for row in bus if row[2] == "o" and (len(row) < 6 or row[5])}
    return wanted - connected


def main():
    if len(sys.argv) < 3:
        print(__doc__.strip().splitlines()[-2], file=sys.stderr)
        return 2
    player = sys.argv[1] if sys.argv[1].startswith("/") else "/" + sys.argv[1]
    with rosbag.Bag(sys.argv[2]) as bag:
        bag_topics = set(bag.get_type_and_topic_info().topics)
    timeout = float(sys.argv[3]) if len(sys.argv) > 3 else 30.0
    socket.setdefaulttimeout(2.0)  # a peer that hangs must not hold the wait past its deadline
    deadline = time.monotonic() + timeout
    missing = None
    while time.monotonic() < deadline:
        try:
            missing = missing_connections(player, bag_topics)
        except (OSError, xmlrpc.client.Error, http.client.HTTPException):
            missing = None  # the player is starting or the master is busy: ask again
        if missing == set():
            return 0
        time.sleep(0.05)
    what = ", ".join(f"{n} on {t}" for t, n in sorted(missing)) if missing else f"{player} did not advertise the bag's topics"
    print(f"wait_bag_connections: not connected after {timeout:g} s: {what}", file=sys.stderr)
    return 1


if __name__ == "__main__":
    sys.exit(main())
