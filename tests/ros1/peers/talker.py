"""rospy talker for the interop tests (run with /usr/bin/python3, never imported).

usage: talker.py TOPIC TYPE(String|Odometry) RATE_HZ [COUNT] [--latch]
Publishes "hello N" (String) or an Odometry with pose.position.x = N.
Prints "ready" once advertised, then one line per message sent.
"""

import sys

import rospy
from nav_msgs.msg import Odometry
from std_msgs.msg import String


def main():
    topic, kind, rate = sys.argv[1], sys.argv[2], float(sys.argv[3])
    count = int(sys.argv[4]) if len(sys.argv) > 4 and sys.argv[4] != "--latch" else 0
    latch = "--latch" in sys.argv
    rospy.init_node("talker", anonymous=True, disable_signals=True)
    cls = String if kind == "String" else Odometry
    pub = rospy.Publisher(topic, cls, queue_size=100, latch=latch)
    print("ready", flush=True)
    r = rospy.Rate(rate)
    n = 0
    while not rospy.is_shutdown() and (count == 0 or n < count):
        if kind == "String":
            msg = String(data=f"hello {n}")
        else:
            msg = Odometry()
            msg.header.frame_id = "odom"
            msg.header.stamp = rospy.Time.now()
            msg.child_frame_id = "base_link"
            msg.pose.pose.position.x = float(n)
            msg.pose.pose.orientation.w = 1.0
        pub.publish(msg)
        print(f"sent {n}", flush=True)
        n += 1
        r.sleep()
    if latch:
        rospy.spin()


if __name__ == "__main__":
    main()
