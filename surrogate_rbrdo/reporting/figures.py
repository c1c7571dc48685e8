"""Saving figures written straight to a path (the library's rig and identification reports).

Run folders save figures themselves (``RunFolder.save_figure``); library functions that write
a report into a folder use :func:`save_figure`: the file is written atomically (a temporary
name, then ``os.replace``) and the figure is closed.

>>> import tempfile, pathlib
>>> plt = pyplot()
>>> fig, ax = plt.subplots()
>>> _ = ax.plot([0, 1], [0, 1]); _ = ax.set_title("line")
>>> with tempfile.TemporaryDirectory() as d:
...     p = save_figure(fig, pathlib.Path(d) / "line.png")
...     p.stat().st_size > 0
True
"""

from __future__ import annotations

import os
import secrets
from pathlib import Path


def pyplot():
    """``matplotlib.pyplot`` on the non-interactive Agg backend (no screen needed)."""
    import matplotlib  # heavy, and the backend must be chosen before pyplot is imported

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save_figure(fig, path: str | Path, *, dpi: int = 120) -> Path:
    """Save ``fig`` to ``path`` atomically (format from the suffix) and close it."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{secrets.token_hex(4)}.tmp")
    fig.savefig(tmp, dpi=dpi, format=path.suffix[1:] or "png")
    os.replace(tmp, path)
    pyplot().close(fig)
    return path
