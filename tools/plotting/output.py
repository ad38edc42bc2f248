"""Saving charts: matplotlib without a display, each chart as PNG and SVG (the report: PNG only),
and the lines on stdout that name what was written."""
import os
import sys

import matplotlib

from .load import InputError

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


def make_folder(out):
    """The output folder, made with its parents where missing."""
    if os.path.exists(out) and not os.path.isdir(out):
        raise InputError(out, "not a folder (a file is in its place)")
    os.makedirs(out, exist_ok=True)


def quiet_stdout():
    """Stdout to /dev/null from here on: nothing more is wanted there, or nothing more can be
    written (and Python would complain of it again at exit)."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError):
        pass


def say(line):
    """A line on stdout. A reader that went away (`cullide plot ... | head -1`) stops the lines,
    not the charts; any other write error (a full disk) is an error naming stdout."""
    try:
        print(line, flush=True)
    except BrokenPipeError:
        quiet_stdout()
    except OSError as e:
        quiet_stdout()
        raise InputError("stdout", e.strerror or str(e)) from None


def save(fig, out, name):
    for ext in SAVE["formats"]:
        path = os.path.join(out, f"{name}.{ext}")
        fig.savefig(path, dpi=120, bbox_inches="tight")
        if SAVE["print"]:
            say(path)
    plt.close(fig)
