"""Where the test bags are, and which topic of each holds poses."""

from __future__ import annotations

from pathlib import Path

REPO = Path(__file__).resolve().parents[3]
SHARED_BAGS = REPO / ".." / "shared" / "bags"
"""Real recordings (../shared/bags beside the repository; see its SOURCES.md)."""
DEMO_BAGS = REPO / "bags"
"""The bags the project generates for its demos."""

HUSKY = ("rl_test1.bag", "/husky_velocity_controller/odom")
ARDRONE = ("rl_test3_groovy.bag", "/ardrone/odometry/raw")
NAV2_ODOM = ("evo_nav2_turtlebot.mcap", "/odom")
NAV2_AMCL = ("evo_nav2_turtlebot.mcap", "/amcl_pose")
AMR_LOCATION = ("amr_rosbag_demo.bag", "/location")
