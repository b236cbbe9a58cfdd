"""The structural-analysis hand-off in ``model.ifc``: an ``IfcStructuralAnalysisModel`` an engineer's FE tool can
start from (IFC4 structural analysis domain).

* One ``IfcStructuralPointConnection`` per node (``N-…`` ids of ``nodes.csv``), a vertex at the node's system
  point: the mesh vertex moved ``depth / 2`` along its node axis (``nodes.csv`` ``axis_*``, pointing into the
  structure), the centroid line of the beam plates hanging ``depth`` from the mesh.
* One ``IfcStructuralCurveMember`` (``RIGID_JOINED_MEMBER``) per mesh edge — every edge carries a beam plate,
  continuous or of one edge — an edge between its two nodes' vertices, named after the plate that carries it
  (``parts.csv`` ``part_id``).  Its ``Axis`` (the member's local z) is the plate's depth direction: the mean of the
  two node axes made orthogonal to the edge; its material a profile set of one rectangle ``thickness × depth`` in
  the beam material, so the section follows the plate (``XDim`` across the plate, ``YDim`` along the axes).
* ``IfcRelConnectsStructuralMember`` joins each member to the connections at its two ends.
* The boundary nodes of the mesh are supports, pinned (translations held, rotations free) — the usual start for
  a gridshell that bears on its edge beam; the engineer changes them to what the design bears on.
* All members and connections are assigned to the analysis model (``IfcRelAssignsToGroup``), which serves the
  building (``IfcRelServicesBuildings``).  The representations are topology (``IfcVertexPoint``, ``IfcEdge``) in
  a ``Reference`` sub-context for the ``GRAPH_VIEW``, as the structural domain asks.

Loads and load cases are left to the engineer: ppfab knows the glass weights (``parts.csv`` ``weight_kg``) but
not the site's wind and snow.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ..contract import node_id

if TYPE_CHECKING:  # pragma: no cover
    from ..records import BuildRecord
    from .ifc import IfcModel


def member_axes(points: np.ndarray, axes: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """The local z axis of each member ``(E, 3)``: the mean of its two end axes made orthogonal to the edge.

    ``points (V, 3)``, ``axes (V, 3)`` unit node axes, ``edges (E, 2)`` vertex pairs.  Where the mean axis runs
    along the edge (it cannot for a beam with depth), the world z (or x) made orthogonal is used.
    """
    d = points[edges[:, 1]] - points[edges[:, 0]]
    d = d / np.linalg.norm(d, axis=1, keepdims=True)
    a = axes[edges[:, 0]] + axes[edges[:, 1]]
    z = a - np.einsum("ij,ij->i", a, d)[:, None] * d
    norm = np.linalg.norm(z, axis=1)
    bad = norm < 1e-9
    if bad.any():
        ref = np.where(np.abs(d[bad, 2:3]) < 0.9, [[0.0, 0.0, 1.0]], [[1.0, 0.0, 0.0]])
        z[bad] = ref - np.einsum("ij,ij->i", ref, d[bad])[:, None] * d[bad]
        norm[bad] = np.linalg.norm(z[bad], axis=1)
    return z / norm[:, None]


def edge_plates(build: "BuildRecord") -> dict[tuple[int, int], str]:
    """``(i, j) → part_id`` (``i < j``) of the beam plate that carries each mesh edge; an edge across a bolted
    splice is carried by the two pieces it joins: ``"B-U00-S00+B-U00-S01"``."""
    out: dict[tuple[int, int], str] = {}
    by_beam: dict[str, list[Any]] = {}
    for p in build.beams.plates:
        nodes = [int(k) for k in p.nodes]
        for a, b in zip(nodes, nodes[1:]):
            out.setdefault((min(a, b), max(a, b)), p.part_id)
        by_beam.setdefault(p.beam_id, []).append(p)
    for pieces in by_beam.values():
        pieces.sort(key=lambda p: p.piece)
        for p, q in zip(pieces, pieces[1:]):
            a, b = int(p.nodes[-1]), int(q.nodes[0])
            if a != b:
                out.setdefault((min(a, b), max(a, b)), f"{p.part_id}+{q.part_id}")
    return out


def add_analysis_model(model: "IfcModel", build: "BuildRecord") -> Any:
    """Add the analysis model of ``build`` to ``model`` (see module docstring); returns the
    ``IfcStructuralAnalysisModel``."""
    f = model.f
    mesh = build.mesh
    qm = mesh.to_quadmesh() if hasattr(mesh, "to_quadmesh") else mesh
    points = np.asarray(qm.vertices, dtype=float)
    axes = np.asarray(build.support.axes, dtype=float)
    axes = axes / np.linalg.norm(axes, axis=1, keepdims=True)
    depth, thickness = float(build.beams.params.depth), float(build.beams.params.thickness)
    system = points + 0.5 * depth * axes
    edges = np.sort(np.asarray(qm.edges, dtype=np.int64), axis=1)
    edges = edges[np.lexsort((edges[:, 1], edges[:, 0]))]
    z = member_axes(system, axes, edges)
    plates = edge_plates(build)
    boundary = set(int(k) for k in np.flatnonzero(qm.topology.boundary_vertices))

    ref = f.create_entity("IfcGeometricRepresentationSubContext", ContextIdentifier="Reference",
                          ContextType="Model", ParentContext=model.context, TargetView="GRAPH_VIEW")
    world = model.site_placement
    pinned = f.create_entity("IfcBoundaryNodeCondition", Name="pinned (ppfab default: change to the bearing)",
                             TranslationalStiffnessX=f.create_entity("IfcBoolean", True),
                             TranslationalStiffnessY=f.create_entity("IfcBoolean", True),
                             TranslationalStiffnessZ=f.create_entity("IfcBoolean", True),
                             RotationalStiffnessX=f.create_entity("IfcBoolean", False),
                             RotationalStiffnessY=f.create_entity("IfcBoolean", False),
                             RotationalStiffnessZ=f.create_entity("IfcBoolean", False))
    vertices: list[Any] = []
    connections: list[Any] = []
    for k, p in enumerate(system):
        vp = f.create_entity("IfcVertexPoint", VertexGeometry=f.create_entity(
            "IfcCartesianPoint", Coordinates=tuple(float(x) for x in p)))
        rep = f.create_entity("IfcTopologyRepresentation", ContextOfItems=ref, RepresentationIdentifier="Reference",
                              RepresentationType="Vertex", Items=[vp])
        vertices.append(vp)
        connections.append(f.create_entity(
            "IfcStructuralPointConnection", GlobalId=model.guid(f"analysis/node/{k}"), Name=node_id(k),
            ObjectPlacement=world, Representation=f.create_entity("IfcProductDefinitionShape",
                                                                  Representations=[rep]),
            AppliedCondition=pinned if k in boundary else None))
    steel = model.material(build.design.beams.material, "steel")
    profile = f.create_entity("IfcRectangleProfileDef", ProfileType="AREA",
                              ProfileName=f"plate {thickness:g} x {depth:g}", XDim=thickness, YDim=depth)
    profiles = f.create_entity("IfcMaterialProfileSet", Name=f"beam plate {thickness:g} x {depth:g}",
                               MaterialProfiles=[f.create_entity("IfcMaterialProfile", Name="beam plate",
                                                                 Material=steel, Profile=profile)])
    members: list[Any] = []
    for e, (i, j) in enumerate(edges):
        i, j = int(i), int(j)
        edge = f.create_entity("IfcEdge", EdgeStart=vertices[i], EdgeEnd=vertices[j])
        rep = f.create_entity("IfcTopologyRepresentation", ContextOfItems=ref, RepresentationIdentifier="Reference",
                              RepresentationType="Edge", Items=[edge])
        plate = plates.get((i, j), "")
        member = f.create_entity(
            "IfcStructuralCurveMember", GlobalId=model.guid(f"analysis/member/{i}-{j}"),
            Name=f"{node_id(i)}/{node_id(j)}", Description=plate or None, ObjectPlacement=world,
            Representation=f.create_entity("IfcProductDefinitionShape", Representations=[rep]),
            PredefinedType="RIGID_JOINED_MEMBER",
            Axis=f.create_entity("IfcDirection", DirectionRatios=tuple(float(x) for x in z[e])))
        members.append(member)
        for end, k in (("start", i), ("end", j)):
            f.create_entity("IfcRelConnectsStructuralMember", GlobalId=model.guid(f"analysis/member/{i}-{j}/{end}"),
                            RelatingStructuralMember=member, RelatedStructuralConnection=connections[k])
    f.create_entity("IfcRelAssociatesMaterial", GlobalId=model.guid("analysis/material"), RelatedObjects=members,
                    RelatingMaterial=profiles)
    analysis = f.create_entity("IfcStructuralAnalysisModel", GlobalId=model.guid("analysis"),
                               Name=f"{model.name} analysis model",
                               Description="beam plates as members on their centroid lines, nodes as rigid "
                                           "connections, boundary nodes pinned", PredefinedType="LOADING_3D",
                               SharedPlacement=world)
    f.create_entity("IfcRelAssignsToGroup", GlobalId=model.guid("analysis/group"),
                    RelatedObjects=members + connections, RelatingGroup=analysis)
    f.create_entity("IfcRelServicesBuildings", GlobalId=model.guid("analysis/building"), RelatingSystem=analysis,
                    RelatedBuildings=[model.building])
    return analysis
