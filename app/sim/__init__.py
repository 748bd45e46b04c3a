"""Simulated plants: actuators, cranes, Delta head, Stewart platforms, winch, pendulum."""
