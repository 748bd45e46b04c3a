"""Bosun: operator HMI and universal-input teleoperation for maritime cranes and robots.

``app`` is the Qt-free core: robot models, solvers, teleoperation, simulation and the
engine.  The PyQt5 GUI lives in ``ui`` and talks to the engine through the protocol.
"""

__version__ = "0.1.0"
