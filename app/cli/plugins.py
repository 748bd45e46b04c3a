"""Commands other packages add (the GUI's ``bosun gui``), under the ``bosun.commands`` entry points."""

from __future__ import annotations

from app.cli.common import _finite_float, _positive_float

PLUGIN_GROUP = "bosun.commands"
HELPERS = {"positive_float": _positive_float, "finite_float": _finite_float}  # handed to each plug-in


def register(sub) -> None:
    """Commands other packages register under the ``bosun.commands`` entry-point group.

    The GUI (package ``ui``) adds ``bosun gui`` this way, so the Qt-free core never imports
    the GUI; each plug-in gets ``register(subparsers, helpers)``.
    """
    from importlib.metadata import entry_points

    for ep in entry_points(group=PLUGIN_GROUP):
        try:
            register = ep.load()
        except ImportError:
            continue  # the plug-in's package is not installed here
        register(sub, HELPERS)
