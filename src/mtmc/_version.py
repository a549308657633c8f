"""The version of mtmc: one module that imports nothing, so that any layer may name it.

The build reads it (``pyproject.toml``), and so does the provenance of every result folder.
"""

__version__ = "0.1.0"
