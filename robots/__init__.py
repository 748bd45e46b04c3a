"""The robot library: robot files (``*.xml``), their schema (``robot.xsd``) and lab layouts (``labs/``).

Installed as the package data of ``app.robots`` (pyproject.toml maps this folder there); Bosun finds it
with ``importlib.resources`` (:func:`app.resources.robot_library`).  No code lives here.
"""
