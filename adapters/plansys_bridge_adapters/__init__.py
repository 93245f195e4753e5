"""Hardware adapter plugins for plansys-bridge (installed as ``plansys_bridge_adapters``)."""
