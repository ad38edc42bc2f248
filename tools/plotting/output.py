"""Saving charts: matplotlib without a display, each chart as PNG and SVG (the report: PNG only)."""
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def finish(fig, ax, out, name, xlabel, ylabel, title, legend_size=None):
    """Axis labels, title, grid and legend of a chart, then save it."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=legend_size)
    save(fig, out, name)


SAVE = {"formats": ("png", "svg"), "print": True}  # the report wants PNGs only, and no paths printed


def save(fig, out, name):
    for ext in SAVE["formats"]:
        path = os.path.join(out, f"{name}.{ext}")
        fig.savefig(path, dpi=120, bbox_inches="tight")
        if SAVE["print"]:
            print(path)
    plt.close(fig)
