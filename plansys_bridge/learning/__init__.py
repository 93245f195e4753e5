"""Learning from recorded missions: how long actions really take and how often
they succeed (``plansys-bridge learn``)."""
