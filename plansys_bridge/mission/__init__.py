"""Run a mission file: knowledge in, plan, performers, execution, summary out.

* :func:`run_mission`, :class:`MissionReport` (``run``): one mission to its end;
* :class:`MissionSession` (``session``): the hub, performers, events and recorder
  of a mission, started and stopped together;
* :func:`load_domain`, :func:`build_knowledge` (``knowledge``): the domain and the
  knowledge, checked against the rest of the file before anything starts;
* :func:`make_clock`, :func:`make_transport` (``transport``): what the file names;
* :func:`in_mission_file` (``file_keys``): errors that name their key in the file.
"""

from __future__ import annotations

from plansys_bridge.mission.file_keys import in_mission_file
from plansys_bridge.mission.knowledge import build_knowledge, load_domain
from plansys_bridge.mission.run import MissionReport, default_missions_dir, plan_now, run_mission
from plansys_bridge.mission.session import MissionSession
from plansys_bridge.mission.transport import make_clock, make_transport

__all__ = [
    "MissionReport",
    "MissionSession",
    "build_knowledge",
    "default_missions_dir",
    "in_mission_file",
    "load_domain",
    "make_clock",
    "make_transport",
    "plan_now",
    "run_mission",
]
