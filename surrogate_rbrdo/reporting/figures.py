"""Saving figures written straight to a path (the library's rig and identification reports).

Run folders save figures themselves (``RunFolder.save_figure``); library functions that write
a report into a folder use :func:`save_figure`: the file goes through the toolkit's one atomic
writer (``core.files.atomic_write_bytes``: a temporary name, mode 0644, then ``os.replace``)
and the figure is closed.

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

import io
from pathlib import Path

from surrogate_rbrdo.core.files import atomic_write_bytes


def pyplot():
    """``matplotlib.pyplot`` on the non-interactive Agg backend (no screen needed)."""
    import matplotlib  # heavy, and the backend must be chosen before pyplot is imported

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save_figure(fig, path: str | Path, *, dpi: int = 120) -> Path:
    """Save ``fig`` to ``path`` atomically (format from the suffix) and close it."""
    path = Path(path)
    buf = io.BytesIO()
    fig.savefig(buf, dpi=dpi, format=path.suffix[1:] or "png")
    atomic_write_bytes(path, buf.getvalue())
    pyplot().close(fig)
    return path
