"""ejsrl.world: the scene graph, mesh import, collisions and virtual-camera rendering."""

from ejsrl.world.collision import CollisionShape, CollisionWorld, collisions, shape_from_node
from ejsrl.world.mesh import MeshFormatError, MeshPart, load_mesh
from ejsrl.world.rendering import BACKGROUND, Realism, render, render_depth
from ejsrl.world.scene import NODE_KINDS, Node, Part, World

__all__ = ["World", "Node", "Part", "NODE_KINDS", "render", "render_depth", "Realism", "BACKGROUND",
           "load_mesh", "MeshPart", "MeshFormatError", "CollisionShape", "CollisionWorld", "shape_from_node", "collisions"]
