"""plansys_bridge.knowledge."""
