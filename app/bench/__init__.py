"""Benchmarks of the running engine: loop timing under load (``bosun bench loop``) and simulation
speed (``bosun bench sim``).  They start engines, so they sit above :mod:`app.engine`."""
