"""plansys-bridge: PlanSys2-style task planning and execution for robots, in Python."""

from plansys_bridge.errors import PlansysBridgeError

__all__ = ["PlansysBridgeError", "__version__"]
__version__ = "0.1.0"
