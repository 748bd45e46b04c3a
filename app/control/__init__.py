"""Controllers: crane-head (TAC) motion compensation."""
