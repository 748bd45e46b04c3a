"""The studies' and reports' figures: matplotlib's pyplot on the file-only Agg backend, and one way to finish
a figure (laid out, written as PNG, closed)."""

from __future__ import annotations

from pathlib import Path


def pyplot():
    """matplotlib.pyplot on the Agg backend: PNG files, no window and no display needed (imported on first use:
    matplotlib takes a while to import, and most commands draw nothing)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save_figure(plt, fig, path: Path, dpi: float | None = None) -> None:
    """Lay ``fig`` out, write it as PNG at ``path`` (``dpi`` None: matplotlib's default) and close it.

    Ctrl-C and SIGTERM wait until the figure is written (safety H94): Agg's renderer calls Python back, and a
    KeyboardInterrupt raised there came out as "ValueError: Invalid bounding box", a traceback instead of
    "interrupted"."""
    from app.errors import DEFERRED

    with DEFERRED:
        fig.tight_layout()
        fig.savefig(path, dpi=dpi)
        plt.close(fig)


def figure_saver(plt, out: Path, title: str, paths: list[Path]):
    """``save(fig, name)``: title, tight layout, PNG at 110 dpi in ``out``, closed, path recorded."""

    def save(fig, name: str) -> None:
        fig.suptitle(title, fontsize=10)
        save_figure(plt, fig, out / name, dpi=110)
        paths.append(out / name)

    return save
