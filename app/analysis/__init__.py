"""Studies: error distribution, trajectory tracking, IK speed against peers, crane-head and VVMC reports."""
