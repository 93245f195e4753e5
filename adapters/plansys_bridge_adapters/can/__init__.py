"""can adapter."""
