"""Transformations of meshes that keep what the paper's constructions made (planar faces, planar polylines,
conicality), grouped by concept:

* :mod:`ppfab.transforms.pp` — F-transforms and parallel meshes by translating the face image (§2.2.3),
  offsets along the node axes, 4D projective maps of the face image (§2.3.5), multi-nets (Remark 3.2);
* :mod:`ppfab.transforms.similarity` — scaling, rotation about z and translation into millimetres;
* :mod:`ppfab.transforms.laguerre` — Laguerre maps ``X ↦ λAX + T`` with ``AᵀJA = J`` (§4.3);
* :mod:`ppfab.transforms.isotropic` — isotropic Möbius maps of the face image (Remark 2.2).
"""
