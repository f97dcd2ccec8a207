"""ejsrl.world: the scene graph, mesh import, collisions and virtual-camera rendering."""

from ejsrl.world.render import BACKGROUND, render
from ejsrl.world.scene import NODE_KINDS, Node, Part, World

__all__ = ["World", "Node", "Part", "NODE_KINDS", "render", "BACKGROUND"]
