"""Importing this module draws one small figure off screen and throws it away: the first figure of a process
pays for loading the fonts, laying out text and building the mathtext parser of a logarithmic axis's labels
(0.08-0.1 s of the drilling plots' 0.3-0.4 s here, issue 20). The drilling loop imports it in the preload
thread while FreeFEM solves (:func:`wendel.loop.overlap.preload`), so its three plots at the end find it done.

No pyplot: a Figure with its own Agg canvas keeps pyplot's global state to the main thread.
"""

from __future__ import annotations

import io

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

_fig = Figure(figsize=(2.0, 1.5))
FigureCanvasAgg(_fig)
_ax = _fig.add_subplot()
_ax.plot([1.0, 10.0, 1e4], [1.0, 2.0, 1.5], marker=".", label="a")
_ax.set_xscale("log")
_ax.set_xlabel("time [s]")
_ax.set_title("t")
_ax.legend(fontsize=7)
_fig.savefig(io.BytesIO(), format="png", dpi=100)
del _fig, _ax
