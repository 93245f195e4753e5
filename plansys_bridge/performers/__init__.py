"""plansys_bridge.performers."""
