"""Marine environment: waves, vessel motion."""
