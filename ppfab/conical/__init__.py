"""Conical meshes (§2.1.3, §2.3.3, §4): cone axes, residuals and offsets at constant face distance
(:mod:`ppfab.conical.cones`), families of oriented spheres (:mod:`ppfab.conical.spheres`) and the §4.3 editing
of conical P meshes by a Möbius transform of their normals (:mod:`ppfab.conical.edit`).
"""
