"""Where the test bags are, and which topic of each holds poses."""

from __future__ import annotations

from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[3]
REAL_BAG_DIRS = (REPO / "tests" / "fixtures" / "bags", REPO / ".." / "shared" / "bags")
"""Real recordings: the one kept in the repository (see tests/fixtures/bags/SOURCES.md),
then a sibling shared/bags folder holding the larger ones, when there is one."""
DEMO_BAGS = REPO / "bags"
"""The bags the project generates for its demos."""

HUSKY = ("rl_test1.bag", "/husky_velocity_controller/odom")
ARDRONE = ("rl_test3_groovy.bag", "/ardrone/odometry/raw")
NAV2_ODOM = ("evo_nav2_turtlebot.mcap", "/odom")
NAV2_AMCL = ("evo_nav2_turtlebot.mcap", "/amcl_pose")
AMR_LOCATION = ("amr_rosbag_demo.bag", "/location")


def real_bag(name: str) -> Path:
    """The recorded bag NAME, or skip the test naming the missing file."""
    for folder in REAL_BAG_DIRS:
        if (folder / name).is_file():
            return (folder / name).resolve()
    pytest.skip(f"real bag {name} not found (looked in tests/fixtures/bags and ../shared/bags)")
