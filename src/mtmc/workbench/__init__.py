"""The measurement-graph workbench: draw a graph of Stryczek in the browser, see its uncertainties.

``mtmc graph edit FILE.toml`` (the ``editor`` extra: ``pip install "mtmc[editor]"``)
serves a page on 127.0.0.1 that draws the graph (places as circles, transitions as
boxes), edits it, and after each edit shows every place's estimate and standard
uncertainty from a short randomised quasi-Monte Carlo run with the GUM beside it; save
writes the file back with its comments and layout kept (``docs/editor.md``).

The server is a thin JSON layer over :mod:`mtmc.graph`, :mod:`mtmc.uncertainty` and
:mod:`mtmc.study` (:mod:`mtmc.workbench.compute`); the page is plain HTML and ES
modules with cytoscape.js vendored (``static/vendor/VENDOR.json``).
"""

from mtmc.workbench.server import Session, create_app, serve

__all__ = ["Session", "create_app", "serve"]
