"""Nesting strategies, one module each (see :mod:`fabrication.nesting.registry`)."""
