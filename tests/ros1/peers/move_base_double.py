"""A move_base action server double in rospy (run with /usr/bin/python3, never imported).

usage: move_base_double.py [NS] [SPEED_M_PER_S] [HOLD_GOAL_ID]
Drives a pretend base from (0, 0) towards each goal at SPEED, 10 feedback messages
per second (base_position), then SUCCEEDED. A goal with x < -50 is aborted with
"no path to goal" (a planner failure); a goal in a frame other than "map" is
rejected (as move_base refuses unknown frames); a cancel preempts.
Prints "ready" when the action server is up and one line per goal outcome.
With HOLD_GOAL_ID the server starts already running that goal (to x = 30), as a
move_base that dropped off the network mid-goal and came back would; every cancel
request is printed as "cancel <id>".
"""

import math
import sys

import actionlib
import rospy
from actionlib_msgs.msg import GoalID
from move_base_msgs.msg import MoveBaseAction, MoveBaseActionGoal, MoveBaseFeedback, MoveBaseResult


def main():
    ns = sys.argv[1] if len(sys.argv) > 1 else "move_base"
    speed = float(sys.argv[2]) if len(sys.argv) > 2 else 2.0
    hold = sys.argv[3] if len(sys.argv) > 3 else ""
    rospy.init_node("move_base_double", anonymous=True, disable_signals=True)
    pose = {"x": 0.0, "y": 0.0}
    server = None

    def execute(goal):
        target = goal.target_pose.pose.position
        frame = goal.target_pose.header.frame_id
        if frame != "map":
            server.set_aborted(MoveBaseResult(), f"unknown frame {frame}")
            print(f"aborted frame {frame}", flush=True)
            return
        if target.x < -50:
            server.set_aborted(MoveBaseResult(), "no path to goal")
            print("aborted no path", flush=True)
            return
        rate = rospy.Rate(10)
        while not rospy.is_shutdown():
            if server.is_preempt_requested():
                server.set_preempted(MoveBaseResult(), "cancelled by client")
                print("preempted", flush=True)
                return
            dx, dy = target.x - pose["x"], target.y - pose["y"]
            dist = math.hypot(dx, dy)
            step = speed / 10.0
            if dist <= step:
                pose["x"], pose["y"] = target.x, target.y
            else:
                pose["x"] += dx / dist * step
                pose["y"] += dy / dist * step
            fb = MoveBaseFeedback()
            fb.base_position.header.frame_id = "map"
            fb.base_position.header.stamp = rospy.Time.now()
            fb.base_position.pose.position.x = pose["x"]
            fb.base_position.pose.position.y = pose["y"]
            fb.base_position.pose.orientation = goal.target_pose.pose.orientation
            server.publish_feedback(fb)
            if dist <= step:
                server.set_succeeded(MoveBaseResult(), "goal reached")
                print("succeeded {:.2f} {:.2f}".format(pose["x"], pose["y"]), flush=True)
                return
            rate.sleep()

    server = actionlib.SimpleActionServer(ns, MoveBaseAction, execute, auto_start=False)
    rospy.Subscriber(
        ns.rstrip("/") + "/cancel", GoalID, lambda m: print(f"cancel {m.id}", flush=True)
    )
    server.start()
    if hold:
        held = MoveBaseActionGoal()
        held.goal_id.id = hold
        held.goal_id.stamp = rospy.Time.now()
        held.goal.target_pose.header.frame_id = "map"
        held.goal.target_pose.pose.position.x = 30.0
        held.goal.target_pose.pose.orientation.w = 1.0
        server.action_server.internal_goal_callback(held)
        print(f"holding {hold}", flush=True)
    print("ready", flush=True)
    rospy.spin()


if __name__ == "__main__":
    main()
