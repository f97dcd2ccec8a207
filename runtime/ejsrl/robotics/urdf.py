"""Load a serial arm from a URDF file into a :class:`~ejsrl.robotics.Robot`.

``load_urdf("ur5.urdf", tip="tool0")`` parses the file with `yourdfpy
<https://github.com/clemense/yourdfpy>`_ (a maintained, dependency-light URDF parser:
``pip install yourdfpy``, or ``pip install ejsgen[urdf]``) and builds a ``Robot`` of
:class:`~ejsrl.robotics.link.ETSLink` links, so every method (``fkine``, ``jacob0``,
``ikine``, ``rne``, ``inertia``, ``accel``...) runs on code generated for the arm, as for
the DH models.

How the URDF maps to the model:

- The chain runs from the root link to ``tip`` (by default the leaf reached through the
  most movable joints; the last such leaf in the file on a tie). Each revolute,
  continuous or prismatic joint on it is one link; fixed joints are folded into the next
  joint's constant transform, or into ``tool`` after the last joint.
- Link frame i is the URDF frame of joint i's child link, turned so that the joint axis
  is its z axis (``T_urdfchild_i = R_axis``, the smallest rotation taking z to the
  axis; the identity when the axis is already z). ``fkine_all`` gives these frames;
  ``robot.urdf_frames`` gives the turns so the URDF frames are ``fkine_all(q)[i] @
  R_axis[i].T``. ``fkine`` is the pose of ``tip``'s frame.
- Inertia: each link collects the URDF links rigidly attached to it (through fixed
  joints, on the chain or beside it); links fixed to the root do not move and are left
  out. Joint limits become ``qlim`` (continuous joints are unlimited), ``<dynamics
  damping>`` the viscous friction ``B`` and ``friction`` the Coulomb friction.
- ``robot.visuals``: per link frame 0..n, the URDF visual geometry in that frame
  (:class:`Visual`); the ``robot`` scene element draws them.

Not supported (an error says so): floating and planar joints on the chain, and mimic
joints on it. Movable joints off the chain (e.g. a gripper's fingers) are held at 0.
"""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .link import ETSLink
from .robot import Robot

__all__ = ["load_urdf", "Visual", "URDFError"]

Array = NDArray[np.float64]

_MOVABLE = ("revolute", "continuous", "prismatic")


class URDFError(ValueError):
    """A URDF file that cannot be made into a serial arm; the text says why."""


@dataclass
class Visual:
    """One piece of a link's visual geometry.

    ``T_link_geom``: (4, 4) pose of the geometry in the model's link frame; ``kind``:
    ``"mesh"`` (``filename``, ``scale`` (3,)), ``"box"`` (``size`` (3,)), ``"cylinder"``
    (``radius``, ``length``, along z) or ``"sphere"`` (``radius``); ``rgba``: the
    material colour, or None.
    """

    kind: str
    T_link_geom: Array
    filename: str = ""
    scale: Array = field(default_factory=lambda: np.ones(3))
    size: Array = field(default_factory=lambda: np.zeros(3))
    radius: float = 0.0
    length: float = 0.0
    rgba: Array | None = None

    def trimeshes(self) -> list[Any]:
        """The geometry as trimesh meshes in the link frame (meshes keep their colours)."""
        import trimesh

        if self.kind == "mesh":
            from ejsrl.world.mesh import load_mesh

            out = []
            for part in load_mesh(self.filename, scale=tuple(self.scale)):
                m = trimesh.Trimesh(part.vertices, part.faces, process=False)
                if part.T_node_part is not None:
                    m.apply_transform(part.T_node_part)
                m.apply_transform(self.T_link_geom)
                m.metadata["rgb"] = part.rgb
                out.append(m)
            return out
        if self.kind == "box":
            m = trimesh.creation.box(extents=self.size)
        elif self.kind == "cylinder":
            m = trimesh.creation.cylinder(radius=self.radius, height=self.length, sections=24)
        else:
            m = trimesh.creation.icosphere(subdivisions=2, radius=self.radius)
        m.apply_transform(self.T_link_geom)
        return [m]


def _yourdfpy() -> Any:
    try:
        import yourdfpy
    except ImportError as exc:  # pragma: no cover - the hint is the point
        raise ImportError(
            "loading URDF files needs the 'yourdfpy' package: pip install yourdfpy "
            "(or pip install 'ejsgen[urdf]')"
        ) from exc
    return yourdfpy


def _axis_turn(axis: Array) -> Array:
    """The smallest rotation (3, 3) taking z to the unit vector ``axis`` (entries within
    1e-12 of 0, ±1 snapped, so a joint about y gives an exact quarter turn)."""
    z = np.array([0.0, 0.0, 1.0])
    c = float(axis @ z)
    if c > 1.0 - 1e-12:
        return np.eye(3)
    if c < -1.0 + 1e-12:
        return np.diag([1.0, -1.0, -1.0])  # half a turn about x
    k = np.cross(z, axis)
    s = float(np.linalg.norm(k))
    k = k / s
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    R = np.eye(3) + s * K + (1.0 - c) * (K @ K)
    R[np.abs(R) < 1e-12] = 0.0
    R[np.abs(R - 1.0) < 1e-12] = 1.0
    R[np.abs(R + 1.0) < 1e-12] = -1.0
    return R


def _h(R: Array) -> Array:
    T = np.eye(4)
    T[:3, :3] = R
    return T


def _inv(T: Array) -> Array:
    out = np.eye(4)
    out[:3, :3] = T[:3, :3].T
    out[:3, 3] = -T[:3, :3].T @ T[:3, 3]
    return out


def _origin(T: Any) -> Array:
    return np.eye(4) if T is None else np.asarray(T, dtype=float).reshape(4, 4)


def _resolve(filename: str, urdf_dir: Path) -> str:
    """A mesh file name of the URDF as a path: ``package://pkg/rel`` is looked up as
    ``rel`` and ``pkg/rel`` beside the URDF file and in its parent folders; a relative name
    is relative to the URDF file's folder."""
    name = filename
    for prefix in ("package://", "file://"):
        if name.startswith(prefix):
            name = name[len(prefix):]
            break
    if os.path.isabs(name) and os.path.exists(name):
        return name
    parts = Path(name).parts
    candidates = [Path(*parts[k:]) for k in range(len(parts))]
    for folder in [urdf_dir, *urdf_dir.parents]:
        for rel in candidates:
            p = folder / rel
            if p.exists():
                return str(p)
    raise URDFError(f"{urdf_dir}: mesh file '{filename}' not found beside the URDF file or in its parent folders")


def _spatial(m: float, T_in: Array, I_c: Array) -> tuple[float, Array, Array]:
    """(mass, first moment m c, inertia about the frame origin) of a body with mass m,
    centre of mass frame ``T_in`` and inertia ``I_c`` about it (in that frame's axes)."""
    c = T_in[:3, 3]
    R = T_in[:3, :3]
    Ic = R @ I_c @ R.T
    return m, m * c, Ic + m * (float(c @ c) * np.eye(3) - np.outer(c, c))


def load_urdf(
    path: str | os.PathLike[str],
    *,
    tip: str | None = None,
    name: str | None = None,
    gravity: ArrayLike = (0.0, 0.0, -9.81),
    load_visuals: bool = True,
) -> Robot:
    """A ``Robot`` made from the URDF file ``path`` (see the module's text for the mapping).

    Args:
        path: the ``.urdf`` file; mesh files are found relative to it (``package://``
            names too, in its folder and the folders above).
        tip: the link whose frame ``fkine`` gives (default: the deepest leaf).
        name: the robot's name (default: the URDF's).
        gravity: world-frame gravity (m/s^2).
        load_visuals: resolve the visual geometry (``robot.visuals``).
    """
    yourdfpy = _yourdfpy()
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"URDF file not found: {path}")
    try:
        urdf = yourdfpy.URDF.load(str(path), build_scene_graph=False, load_meshes=False)
    except Exception as exc:  # yourdfpy raises several kinds of errors
        raise URDFError(f"{path}: not a readable URDF file: {exc}") from exc
    rob = urdf.robot
    links = {link.name: link for link in rob.links}
    joint_of_child = {j.child: j for j in rob.joints}
    children: dict[str, list[Any]] = {}
    for j in rob.joints:
        if j.parent not in links or j.child not in links:
            raise URDFError(f"{path}: joint '{j.name}' joins unknown links '{j.parent}' -> '{j.child}'")
        children.setdefault(j.parent, []).append(j)
    roots = [n for n in links if n not in joint_of_child]
    if len(roots) != 1:
        raise URDFError(f"{path}: a URDF tree has one root link, found {len(roots)}: {roots}")
    root = roots[0]

    def chain_to(link: str) -> list[Any]:
        out = []
        while link in joint_of_child:
            j = joint_of_child[link]
            out.append(j)
            link = j.parent
        return out[::-1]

    if tip is None:
        order = {n: k for k, n in enumerate(links)}
        leaves = [n for n in links if n not in children]
        tip = max(leaves, key=lambda n: (sum(j.type in _MOVABLE for j in chain_to(n)), order[n]))
    elif tip not in links:
        close = sorted(links, key=lambda n: -_similar(n, tip))[:3]
        raise URDFError(f"{path}: no link named '{tip}'; links include {close}")
    chain = chain_to(tip)
    movable = [j for j in chain if j.type in _MOVABLE]
    for j in chain:
        if j.type not in _MOVABLE + ("fixed",):
            raise URDFError(f"{path}: joint '{j.name}' is of type '{j.type}'; only revolute, continuous, "
                            "prismatic and fixed joints can be on an arm's chain")
        if j.mimic is not None and j.type != "fixed":
            raise URDFError(f"{path}: joint '{j.name}' mimics '{j.mimic.joint}'; mimic joints on the chain "
                            "are not supported (choose another tip)")
    if not movable:
        raise URDFError(f"{path}: no movable joint between '{root}' and '{tip}'")

    # which model frame each URDF link is rigid with, and its pose in that frame
    chain_links = [root] + [j.child for j in chain]
    frame_of: dict[str, tuple[int, Array]] = {root: (0, np.eye(4))}
    turns = [np.eye(3)]
    ets_links: list[ETSLink] = []
    T_acc = np.eye(4)  # fixed transforms since the last joint, in the last model frame
    idx = 0
    for j in chain:
        T_j = _origin(j.origin)
        if j.type == "fixed":
            T_acc = T_acc @ T_j
            frame_of[j.child] = (idx, T_acc.copy())
            continue
        axis = np.asarray(j.axis if j.axis is not None else (1.0, 0.0, 0.0), dtype=float)
        if np.linalg.norm(axis) < 1e-12:
            raise URDFError(f"{path}: joint '{j.name}' has a zero axis")
        axis = axis / np.linalg.norm(axis)
        Ra = _axis_turn(axis)
        origin = T_acc @ T_j @ _h(Ra)
        idx += 1
        turns.append(Ra)
        frame_of[j.child] = (idx, _h(Ra.T))  # T_frame_childlink
        T_acc = _h(Ra.T)
        kw: dict[str, Any] = {"name": j.name, "sigma": "P" if j.type == "prismatic" else "R"}
        lim = j.limit
        if j.type != "continuous" and lim is not None and lim.lower is not None and lim.upper is not None \
                and lim.upper > lim.lower:
            kw["qlim"] = (float(lim.lower), float(lim.upper))
        dyn = j.dynamics
        if dyn is not None:
            kw["B"] = float(dyn.damping or 0.0)
            kw["Tc"] = float(dyn.friction or 0.0)
        ets_links.append(ETSLink(origin, **kw))
    tool = T_acc

    # rigidly attached links off the chain (through fixed joints, or movable ones held at 0)
    stack = list(chain_links)
    while stack:
        parent = stack.pop()
        for j in children.get(parent, []):
            if j.child in frame_of:
                continue
            if j.type in _MOVABLE:
                warnings.warn(f"{path}: joint '{j.name}' is not on the chain to '{tip}'; it is held at 0",
                              stacklevel=2)
            k, T = frame_of[parent]
            frame_of[j.child] = (k, T @ _origin(j.origin))
            stack.append(j.child)

    # inertia of each model link: the URDF links rigid with it (not the root's: they do not move)
    n = len(ets_links)
    acc = [[0.0, np.zeros(3), np.zeros((3, 3))] for _ in range(n + 1)]
    for lname, (k, T) in frame_of.items():
        inert = links[lname].inertial
        if inert is None or not inert.mass:
            continue
        I_c = np.zeros((3, 3)) if inert.inertia is None else np.asarray(inert.inertia, dtype=float)
        m, h, I_o = _spatial(float(inert.mass), T @ _origin(inert.origin), I_c)
        acc[k][0] += m
        acc[k][1] = acc[k][1] + h
        acc[k][2] = acc[k][2] + I_o
    for k, link in enumerate(ets_links, start=1):
        m, h, I_o = acc[k]
        if m > 0:
            c = h / m
            link.m = m
            link.r = c
            link.I = I_o - m * (float(c @ c) * np.eye(3) - np.outer(c, c))

    robot = Robot(ets_links, name=name or rob.name or path.stem, tool=tool, gravity=gravity)
    robot.joint_names = [j.name for j in movable]
    #: R_axis per link frame 0..n: URDF child frame = fkine_all(q)[i] @ R_axis[i].T
    robot.urdf_frames = np.array([_h(R) for R in turns])  # type: ignore[attr-defined]
    robot.urdf_path = str(path)  # type: ignore[attr-defined]
    robot.link_names = [root] + [j.child for j in movable]  # type: ignore[attr-defined]
    robot.tip = tip  # type: ignore[attr-defined]
    if load_visuals:
        materials = {m.name: m for m in rob.materials if m.name}
        visuals: list[list[Visual]] = [[] for _ in range(n + 1)]
        for lname, (k, T) in frame_of.items():
            for v in links[lname].visuals:
                vis = _visual(v, T, path.parent, materials)
                if vis is not None:
                    visuals[k].append(vis)
        robot.visuals = visuals
    return robot


def _visual(v: Any, T_frame_link: Array, urdf_dir: Path, materials: dict[str, Any]) -> Visual | None:
    g = v.geometry
    if g is None:
        return None
    T = T_frame_link @ _origin(v.origin)
    rgba = None
    mat = v.material
    if mat is not None:
        color = mat.color if mat.color is not None else getattr(materials.get(mat.name), "color", None)
        if color is not None:
            rgba = np.asarray(color.rgba, dtype=float)
    if g.mesh is not None:
        scale = np.ones(3) if g.mesh.scale is None else np.broadcast_to(np.asarray(g.mesh.scale, float), (3,)).copy()
        return Visual("mesh", T, filename=_resolve(g.mesh.filename, urdf_dir), scale=scale, rgba=rgba)
    if g.box is not None:
        return Visual("box", T, size=np.asarray(g.box.size, dtype=float), rgba=rgba)
    if g.cylinder is not None:
        return Visual("cylinder", T, radius=float(g.cylinder.radius), length=float(g.cylinder.length), rgba=rgba)
    if g.sphere is not None:
        return Visual("sphere", T, radius=float(g.sphere.radius), rgba=rgba)
    return None


def _similar(a: str, b: str) -> float:
    import difflib

    return difflib.SequenceMatcher(None, a, b).ratio()
