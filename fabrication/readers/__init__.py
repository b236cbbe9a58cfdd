"""Readers of a finished build: the records of :mod:`fabrication.model` from an output folder
(:func:`open_build`, one module per kind of file) or from a build in memory (:func:`package_of`).

Beside the writers (layer ``files``): a reader may use the contract and the writers' own helpers, nothing above.
"""

from .errors import BuildReadError
from .folder import open_build
from .memory import package_of

__all__ = ["BuildReadError", "open_build", "package_of"]
