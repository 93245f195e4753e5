"""Sensing rules: sensor values (MAVLink, CAN, ROS topics) into the knowledge.

:mod:`.expressions` parses rule conditions, :mod:`.rules` decides what a sample
means (hysteresis), :mod:`.load` checks a mission's rules, :mod:`.engine` writes
through the problem expert with rate limits, :mod:`.source` is the plugin base
class and its registry.
"""
