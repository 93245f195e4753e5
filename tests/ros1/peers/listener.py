"""rospy listener for the interop tests (run with /usr/bin/python3, never imported).

usage: listener.py TOPIC TYPE(String|Odometry)
Prints "ready" once subscribed, then one line per message: "got <data>" for String,
"got <x> <frame_id> <seq>" for Odometry.
"""

import sys

import rospy
from nav_msgs.msg import Odometry
from std_msgs.msg import String


def main():
    topic, kind = sys.argv[1], sys.argv[2]
    rospy.init_node("listener", anonymous=True, disable_signals=True)
    if kind == "String":
        rospy.Subscriber(topic, String, lambda m: print(f"got {m.data}", flush=True))
    else:
        rospy.Subscriber(
            topic,
            Odometry,
            lambda m: print(
                f"got {m.pose.pose.position.x} {m.header.frame_id} {m.header.seq}",
                flush=True,
            ),
        )
    print("ready", flush=True)
    rospy.spin()


if __name__ == "__main__":
    main()
