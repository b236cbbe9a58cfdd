"""Torsion-free support structures (§2.2, Def. 2.3): node axes and support planes — the one source of them.

:func:`support_structure` (:mod:`ppfab.support.select`) picks a method from the registry
(:mod:`ppfab.support.registry`): ``pp``, ``p``, ``conical``, ``parallel``, one module each.
:class:`SupportStructure` (:mod:`ppfab.support.structure`) holds the result; :class:`SupportParams` is the
``[support]`` table of a design file.
"""
