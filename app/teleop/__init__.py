"""Universal input: devices, profiles and the mapping of eqs. (1), (2) and (7)."""
