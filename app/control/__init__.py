"""Controllers: the crane-head (TAC) joint servos and the cooperative crane."""
