"""Studies and benchmarks: error distribution, trajectory tracking, speed."""
