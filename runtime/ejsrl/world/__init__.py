"""ejsrl.world: the scene graph, mesh import, collisions and virtual-camera rendering."""

from ejsrl.world.collision import CollisionShape, CollisionWorld, collisions, shape_from_node
from ejsrl.world.mesh import MeshFormatError, MeshPart, load_mesh
from ejsrl.world.rendering import BACKGROUND, Realism, render, render_depth
from ejsrl.world.scene import (
    NODE_KINDS,
    Arrow,
    Box,
    CameraNode,
    Cylinder,
    Frame,
    Grid,
    Group,
    Line,
    MeshNode,
    Node,
    Part,
    Points,
    Sphere,
    Text3D,
    Trail,
    World,
)

# the scene's node kinds too, so a script builds a world from one import (``from ejsrl.world
# import World, Box, render``): they lived only in ejsrl.world.scene (session 11's trial)
__all__ = ["World", "Node", "Part", "NODE_KINDS", "render", "render_depth", "Realism", "BACKGROUND",
           "Box", "Sphere", "Cylinder", "Arrow", "Line", "Trail", "Points", "Frame", "Grid", "Text3D", "MeshNode", "Group",
           "CameraNode", "load_mesh", "MeshPart", "MeshFormatError", "CollisionShape", "CollisionWorld", "shape_from_node",
           "collisions"]
