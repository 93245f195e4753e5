"""PlanSys2's terminal: commands over the knowledge, the planner and the executor.

:class:`Terminal` runs one command line at a time (:mod:`.core`); the REPL adds
line editing, history and tab completion (:mod:`.repl`, :mod:`.completion`); a
:class:`Runner` (:mod:`.runner`, :mod:`.mission_runner`) executes plans on a hub.
"""

from plansys_bridge.terminal.core import Terminal, TerminalError
from plansys_bridge.terminal.help import HELP
from plansys_bridge.terminal.runner import Actor, Runner

__all__ = ["HELP", "Actor", "Runner", "Terminal", "TerminalError"]
