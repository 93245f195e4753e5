"""rospy side of bench_ros1.py (run with /usr/bin/python3; the project never imports rospy).

usage: ros1_rospy_peer.py pub TYPE LATENCY_N RATE_HZ BURST_N
       ros1_rospy_peer.py sub TYPE LATENCY_N BURST_N
TYPE is String (10 kB) or Odometry. The publisher sends LATENCY_N stamped messages at
RATE_HZ, then BURST_N as fast as it can; the subscriber prints one JSON line with the
latencies (s) of the first phase and the burst's message count and duration.
"""

import json
import sys
import time

import rospy
from nav_msgs.msg import Odometry
from std_msgs.msg import String

PAD = "x" * 10240


def make(kind, i):
    now = time.time()
    if kind == "String":
        return String(data=f"{i} {now:.9f} {PAD}")
    msg = Odometry()
    msg.header.seq = i
    msg.header.stamp = rospy.Time.from_sec(now)
    msg.header.frame_id = "odom"
    msg.pose.pose.position.x = float(i)
    return msg


def read(kind, msg):
    if kind == "String":
        i, stamp, _ = msg.data.split(" ", 2)
        return int(i), float(stamp)
    return int(msg.pose.pose.position.x), msg.header.stamp.to_sec()


def main():
    role, kind = sys.argv[1], sys.argv[2]
    cls = String if kind == "String" else Odometry
    rospy.init_node(f"bench_{role}", anonymous=True, disable_signals=True)
    if role == "pub":
        lat_n, rate, burst_n = int(sys.argv[3]), float(sys.argv[4]), int(sys.argv[5])
        pub = rospy.Publisher("/bench", cls, queue_size=10000, tcp_nodelay=True)
        print("ready", flush=True)
        while pub.get_num_connections() < 1:
            time.sleep(0.01)
        time.sleep(0.5)
        for i in range(lat_n):
            pub.publish(make(kind, i))
            time.sleep(1.0 / rate)
        time.sleep(0.5)
        for i in range(lat_n, lat_n + burst_n):
            pub.publish(make(kind, i))
        time.sleep(3.0)
        return
    lat_n, burst_n = int(sys.argv[3]), int(sys.argv[4])
    lat, burst = [], []

    def on_msg(msg):
        now = time.time()
        i, stamp = read(kind, msg)
        if i < lat_n:
            lat.append(now - stamp)
        else:
            burst.append(now)

    rospy.Subscriber("/bench", cls, on_msg, tcp_nodelay=True, queue_size=10000)
    print("ready", flush=True)
    deadline = time.time() + 120
    last = 0
    while time.time() < deadline:
        time.sleep(1.0)
        if burst and len(burst) == last:
            break
        last = len(burst)
    span = (burst[-1] - burst[0]) if len(burst) > 1 else 0.0
    print(json.dumps({"latency_s": lat, "burst_received": len(burst), "burst_s": span}), flush=True)


if __name__ == "__main__":
    main()
